"""make bench: speed figures (not a test). Sections (``python -m drystone bench --only ...``):

``running_bond``  the 40-block running-bond wall (8.64 x 4 x 0.8 m, 5 courses of 8,
                  K_n = 2e8 N/m^3, 2300 kg/m^3, on a fixed platform) under gravity, for
                  YADE's stock law and ours (on YADE's contact geometry and on the native
                  one; on the native one with each step ``engine`` the runner offers), on 1
                  and 2 threads: ms per step, steps per second, active contacts and the share
                  of the step spent in our per-step Python engine; the compiled step on one
                  thread is timed ``REPEATS`` times (the fastest kept) and set against the
                  goal of issue 14 (``GOAL_MS``, ``GOAL_SPEEDUP`` over the issue's
                  ``BASELINE_MS``; this run's numpy step beside it).
``scale``         running-bond and irregular walls of about 40, 500 and 2000 stones, and
                  polygonal walls of 500 (``POLYGONAL``: a third of its stones re-entrant,
                  each several convex parts, one body) and 2000 (that face four times
                  along the wall, ``POLYGONAL_TILES``) under
                  gravity for a few hundred steps (our law, native geometry, one thread): ms
                  per step, contacts, us per contact-step, the growth exponent of the cost
                  with the number of stones (least-squares slope of log ms/step on log N),
                  and the contact search (``drystone.mechanics.overlap.contacts_with_patches``) timed
                  alone on the settled positions: its broad phase and its exact clip; the
                  run's peak memory per stone and per further stone.
``threads``       the 40-block wall on 1 and 2 threads, alone and with a second identical
                  run going in a background process (two jobs on the machine, as in a
                  sweep), and the thread count this suggests.
``sacsayhuaman``  the Sacsayhuaman section's analyses on one core against the paper's
                  Abaqus/Explicit times on 8 cores (ratio and speed-up).
``limit``         rigid-block limit analysis (``drystone.analyses.limit``, no YADE): the
                  Sacsayhuaman section (33 free stones) and a running-bond wall of 1000
                  stones (``LIMIT_WALL``): seconds to read the geometry, to find the
                  interfaces and to solve the LP towards +y (associative; the
                  non-associative iteration on the section too), against ``LIMIT_GOALS_S``.
``fragility_ida`` ``python -m drystone fragility`` by IDA (hunt-and-fill) on
                  cases/sacsayhuaman/record.toml over the FEMA P695 far-field records
                  (component a; ``--records N``: the first N, default all 22) on ``--workers``
                  (2) processes: runs used, runs per record, wall time, core-minutes (the
                  runs' own wall times summed), seconds per run and per simulated second,
                  the fitted theta and beta, and the whole set's wall time extrapolated from
                  the records run (runs per record x seconds per run x 22 / workers; said to
                  be an extrapolation when fewer than 22 ran), against ``FRAGILITY_GOAL_MIN``.
                  Its runs stay in results/bench/fragility_ida/ (a rerun reuses them by
                  fingerprint); ``--tolerance`` (g, ``FRAGILITY_TOLERANCE``) and
                  ``--duration`` (s of each record from 1 s before its peak; default whole)
                  trade precision for runs and simulated time.
``profile``       each scale wall's run (500 stones by default) replayed outside YADE in one
                  compiled call (``transient``: from rest, gravity ramped, as the run) and
                  sampled by ``perf`` (``drystone.kernel_profile``): the share of the step of
                  each kernel and of each phase (clip, damping, law, ...), measured inside
                  the compiled loop; skipped, saying why, where perf is missing (Debian:
                  linux-perf).
``compile``       the 40-block wall for ``WARM`` steps through the compiled step in a fresh
                  process on an empty numba cache (what the first run after a change of the
                  kernels' sources, or on a fresh clone, pays), then again on the cache it
                  left: the wall seconds of each, their difference (the compilation) and the
                  kernels' compiled overloads (numba's cache files).

``--baseline COMMIT`` (``drystone.bench_baseline``; alone unless ``--only`` names sections too):
                  the scale section of an earlier commit, in a git worktree, and of this
                  tree, run back to back in ``--rounds`` alternating rounds (2): both trees'
                  ms/step in every round and the speed-ups of the fastest and of the medians
                  (a speed goal over a commit, both figures from one machine).

ms per step: a run's YADE wall time has a fixed start-up (about a second: the first step
loads the compiled kernels) besides its steps, so each measured run goes with a short one
(``WARM`` steps) of the same case: ms/step is the slope (wall_long - wall_short) / (steps
difference) and the start-up the intercept; the whole run's mean (``ms_per_step_run``),
what the figures before were, is kept beside it.

Every figure goes to results/bench/bench.json with the machine's facts (cores, load
average at the start, YADE version); a partial run (``--only``) replaces its sections
there and keeps the others, and a scale run of some walls or sizes (``--walls``,
``--sizes``) replaces only their rows (each row says when it was measured).
"""
from __future__ import annotations

import inspect
import json
import math
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.mechanics import laws

from drystone import paths, runner, units

SECTIONS = ("running_bond", "scale", "threads", "sacsayhuaman", "limit", "fragility_ida", "compile", "profile")

CASE = {
    "case": {"name": "bench_running_bond", "geometry": {"generator": "running_bond"}},
    "stages": [{"type": "gravity", "duration": 1.0, "ramp": 0.2}],
    "output": {"interval": 0.02},
}

#: the speed goal of the compiled step on the 40-block wall (issue 14): at most this many ms
#: per step on one thread, and at least this many times faster than the package's step when
#: the goal was set ("today's": ``BASELINE_MS``, the issue's figure, ~1.6 ms/step on a quiet
#: 2-core machine, 1.47 ms of it Python); the numpy step of the same bench run (``python``
#: engine, which has been made faster since) is reported beside it
GOAL_MS, GOAL_SPEEDUP, BASELINE_MS = 0.25, 6.0, 1.6
#: the compiled step on one thread is timed this many times, the fastest kept (the least
#: disturbed by other jobs: its steps are short, so another process's burst shows)
REPEATS = 3

#: (law, detection) pairs measured: the stock law on its only geometry, ours on both
VARIANTS = (("stock_volumetric", "yade"), ("penalty_coulomb", "yade"), ("penalty_coulomb", "native"))

#: per-step engines of our law on the native geometry (``runner.run_dict(..., engine=)``)
ENGINES = ("python", "compiled")

#: steps of the short run that measures a run's fixed start-up
WARM = 20
DISTURBED = "  DISTURBED (sources changed since the start, or another job): run again"


def engine_supported() -> bool:
    """Whether ``runner.run_dict`` takes an ``engine`` option (itself, or through **kw
    passed on to ``runner.run``)."""
    p = inspect.signature(runner.run_dict).parameters
    if "engine" in p:
        return True
    if any(v.kind == v.VAR_KEYWORD for v in p.values()):
        return "engine" in inspect.signature(runner.run).parameters
    return False


def machine() -> dict:
    """Facts of the machine the figures come from."""
    try:
        yade = subprocess.run(["dpkg-query", "-W", "-f", "${Version}", "yade"], capture_output=True, text=True,
                              timeout=10).stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        yade = "unknown"
    return {"cores": os.cpu_count(), "load_average_at_start": list(os.getloadavg()), "yade_version": yade,
            "python": platform.python_version(), "machine": platform.machine(),
            "time": time.strftime("%Y-%m-%d %H:%M:%S %z")}


# -- timing runs ------------------------------------------------------------------------------

def steady_rate(steps_short: int, wall_short: float, steps_long: int, wall_long: float) -> tuple[float, float]:
    """(ms per step, start-up s) of wall = start-up + steps x ms/step through two runs."""
    if steps_long <= steps_short:
        raise ValueError("the long run needs more steps than the short one")
    per = (wall_long - wall_short) / (steps_long - steps_short)
    return 1e3 * per, wall_short - per * steps_short


def disturbed(ms_per_step: float, startup_s: float, sources_changed: bool = False) -> bool:
    """Whether a (long, short) pair of runs was disturbed: the package's sources changed
    since ``prime`` (a kernel compiled during a run, tens of seconds, which a long run
    spreads over its steps), a start-up outside [-2, 10] s (it is about a second: a compile
    during the short run, another job starting or ending), or no positive cost per step."""
    return sources_changed or not (ms_per_step > 0 and -2.0 <= startup_s <= 10.0)


def sources_stamp() -> float:
    """Latest modification time of the package's Python sources (s since the epoch)."""
    return max(p.stat().st_mtime for p in paths.PACKAGE.rglob("*.py"))


#: ``sources_stamp`` when ``prime`` ran (None: not primed)
_PRIMED: list = [None]


def warm_case(case: dict, dt: float, steps: int = WARM) -> dict:
    """``case`` cut to ``steps`` steps of ``dt`` under gravity (its geometry, one sample)."""
    d = steps * dt
    return dict(case, case=dict(case["case"], name=case["case"]["name"] + "_warm"),
                stages=[{"type": "gravity", "duration": d, "ramp": 0.5 * d}], output={"interval": d})


def timed_run(case: dict, workdir: Path, tag: str, threads: int = 1, overrides=(), step_engine: str | None = None,
              **extra) -> dict:
    """Run ``case`` and its short twin (``warm_case``), with ``step_engine`` if given (else
    the runner's default); the row of figures (``extra`` first)."""
    kw = dict(threads=threads, quiet=True, overrides=list(overrides),
              **({"engine": step_engine} if step_engine else {}))
    out = workdir / tag
    s = runner.run_dict(case, workdir / f"{tag}.toml", out_dir=out, **kw)
    r = s["run"]
    w = runner.run_dict(warm_case(case, r["dt_s"]), workdir / f"{tag}_warm.toml", out_dir=workdir / f"{tag}_warm",
                        **kw)["run"]
    ms, startup = steady_rate(w["steps"], w["wall_time_s"], r["steps"], r["wall_time_s"])
    info = json.loads((out / "run_info.json").read_text())
    py = r.get("python_us_per_step")
    return dict(extra, threads=threads, ms_per_step=ms, steps_per_s=1e3 / ms if ms > 0 else math.nan,
                startup_s=startup, disturbed=disturbed(ms, startup, _PRIMED[0] not in (None, sources_stamp())),
                ms_per_step_run=r["us_per_step"] / 1e3,
                contacts=info["max_contacts"],
                final_contacts=info.get("final_contacts"), python_ms_per_step=None if py is None else py / 1e3,
                steps=r["steps"], warm_steps=w["steps"], dt_s=r["dt_s"], wall_s=r["wall_time_s"],
                engine_used=info.get("engine"), max_rss_mib=info.get("max_rss_mib"), out=str(out))


def prime(workdir: Path) -> None:
    """A few steps of the 40-block wall with each step engine (and our law on YADE's
    geometry), so that the compiled kernels are in numba's cache before anything is
    timed (a first run after a change compiles them: minutes)."""
    _PRIMED[0] = sources_stamp()
    dt = time_step(build_wall(CASE["case"]["geometry"]))
    runs = [("native", e) for e in (ENGINES if engine_supported() else (None,))] + [("yade", None)]
    for detection, engine in runs:
        tag = f"prime_{detection}_{engine or 'default'}"
        runner.run_dict(warm_case(CASE, dt, 5), workdir / f"{tag}.toml", out_dir=workdir / tag, quiet=True,
                        overrides=["contact.law=penalty_coulomb", f"contact.detection={detection}"],
                        **({"engine": engine} if engine else {}))


# -- a: the 40-block wall ---------------------------------------------------------------------

def measure(law: str, detection: str, threads: int, workdir: Path, engine: str | None = None,
            repeats: int = 1) -> dict:
    """One row of the 40-block section: the fastest of ``repeats`` timed runs."""
    tag = f"{law}_{detection}_{threads}" + (f"_{engine}" if engine else "")
    rows = [timed_run(CASE, workdir, tag, threads, [f"contact.law={law}", f"contact.detection={detection}"], engine,
                      law=law, detection=detection, engine=engine or "default") for _ in range(repeats)]
    r = min(rows, key=lambda x: x["ms_per_step"] if x["ms_per_step"] > 0 else math.inf)
    r["repeats"] = [x["ms_per_step"] for x in rows]
    del r["out"]
    return r


def _repeats(r: dict) -> str | None:
    """The ms/step of a row's timed runs, "a, b, c" (None for a row timed once)."""
    reps = r.get("repeats") or []
    return ", ".join(f"{x:.3f}" for x in reps) if len(reps) > 1 else None


def goal(rows: list[dict]) -> dict | None:
    """The issue-14 goal on the 40-block wall's rows: the compiled step on one thread against
    ``GOAL_MS`` and against ``GOAL_SPEEDUP`` x the issue's ``BASELINE_MS``; beside it, the
    ratio to this run's numpy step (``python`` engine, one thread). ``text`` says it in one
    sentence (printed here, and the Speed block of docs/physics.md reads it)."""
    one = {r.get("engine_used"): r for r in rows
           if laws.get(r["law"]).engine("compiled", r["detection"]) == "compiled" and r["threads"] == 1}
    c, p = one.get("compiled"), one.get("python")
    if c is None:
        return None
    ms = c["ms_per_step"]
    out = {"compiled_ms": ms, "goal_ms": GOAL_MS, "ms_met": ms <= GOAL_MS, "baseline_ms": BASELINE_MS,
           "speedup": BASELINE_MS / ms, "goal_speedup": GOAL_SPEEDUP, "speedup_met": BASELINE_MS / ms >= GOAL_SPEEDUP}
    text = (f"compiled step {ms:.3f} ms/step on one thread (goal <= {GOAL_MS} ms: {'met' if out['ms_met'] else 'not met'}), "
            f"{out['speedup']:.1f}x the {BASELINE_MS} ms/step of the uncompiled step it replaced (goal >= {GOAL_SPEEDUP:.0f}x: "
            f"{'met' if out['speedup_met'] else 'not met'})")
    if p is not None:
        out.update(python_ms=p["ms_per_step"], numpy_speedup=p["ms_per_step"] / ms)
        text += f"; {out['numpy_speedup']:.1f}x this run's numpy step ({p['ms_per_step']:.2f} ms/step)"
    if _repeats(c):
        text += f"; the fastest of {len(c['repeats'])} runs ({_repeats(c)} ms/step)"
    out["text"] = text
    return out


def _print_row(r: dict) -> None:
    """One row of the 40-block section, as measured (``measure``)."""
    py = f"python {r['python_ms_per_step']:6.2f} ms/step  " if r["python_ms_per_step"] is not None else ""
    rep = f" (fastest of {_repeats(r)})" if _repeats(r) else ""
    print(f"  {r['law']:17s} {r['detection']:6s} {r['engine']:8s} {r['threads']} thread(s): {r['ms_per_step']:7.3f} "
          f"ms/step{rep}  {r['steps_per_s']:7.1f} steps/s  {r['contacts']:4d} contacts  {py}"
          f"(whole run {r['ms_per_step_run']:.2f} ms/step, start-up {r['startup_s']:.1f} s; "
          f"{r['steps']} steps of {r['dt_s']:.2e} s){DISTURBED if r['disturbed'] else ''}", flush=True)


def running_bond_section(workdir: Path) -> list[dict]:
    """Section a: the 40-block wall, each law and geometry (and engine) on 1 and 2 threads."""
    print("40-block running-bond wall under gravity (1 s):", flush=True)
    engines = ENGINES if engine_supported() else (None,)
    if engines == (None,):
        print("  compiled step not available (runner.run_dict takes no 'engine'): our law on the native "
              "geometry runs the Python step only", flush=True)
    rows = []
    for law, detection in VARIANTS:
        # the compiled step is the native geometry's; on YADE's, our law has the Python one
        yade_engine = "python" if engines != (None,) and "python" in laws.get(law).engines else None
        for engine in (engines if detection == "native" else (yade_engine,)):
            for threads in (1, 2):
                rep = REPEATS if (engine == "compiled" and threads == 1) else 1
                rows.append(measure(law, detection, threads, workdir, engine, rep))
                _print_row(rows[-1])
    g = goal(rows)
    if g is not None:
        print(f"  goal: {g['text']}", flush=True)
    return rows


# -- b: scale ---------------------------------------------------------------------------------

#: stones of the scale section's walls (about; the irregular walls' counts are drawn)
SIZES = (40, 500, 2000)
WALLS = ("running_bond", "irregular", "polygonal")
#: the sizes a wall kind is built at, where not SIZES: the polygonal wall at 500 stones and at
#: 2000, the 500-stone face drawn once and laid ``POLYGONAL_TILES`` times along the wall (its
#: generator's repairs make a 2000-stone face slow to draw: more than 15 min)
WALL_SIZES = {"polygonal": (500, 2000)}
POLYGONAL_TILES = {2000: 4}
#: walls of these sizes are also run on ``THREADS_2`` threads (the compiled step's search
#: over threads: ``contact_step.CompiledStep``'s ``threads``): ms/step and the parallel
#: efficiency t1 / (2 t2)
THREADED_SIZES = (2000,)
#: the polygonal wall (drystone/geometry/polygonal_wall.py): a 12 x 5 m face of stones 0.25-0.5 m
#: in equivalent diameter (500 stones at seed 0), re-entrant stones (several convex parts)
#: r = 0.5 of the convex ones, LAYOUT's thickness
POLYGONAL = {"length": 12.0, "height": 5.0, "stone_size": [0.25, 0.5], "reentrant": 0.5}
#: stones about 0.6 m long, 0.3 m high, 0.6 m deep (ashlar size), 2300 kg/m^3, K_n 2e8 N/m^3
STONE_LENGTH, COURSE_HEIGHT, THICKNESS = 0.6, 0.3, 0.6
#: (courses, stones per course) of each size
LAYOUT = {40: (5, 8), 500: (20, 25), 2000: (40, 50)}


def wall_geometry(kind: str, size: int, seed: int = 0) -> dict:
    """The case-file geometry table of a scale wall: ``kind`` running_bond (exactly
    courses x per_course stones) or irregular (stone lengths 0.45-0.75 m drawn along the
    course, leaning head joints and sloping bed joints: about the same count), ``size``
    one of LAYOUT's keys. Both are LAYOUT's courses of COURSE_HEIGHT, stones about
    STONE_LENGTH long, THICKNESS deep, first course fixed."""
    if size not in LAYOUT:
        raise ValueError(f"wall size {size!r}: one of {sorted(LAYOUT)}")
    courses, per = LAYOUT[size]
    length, height = per * STONE_LENGTH, courses * COURSE_HEIGHT
    if kind == "running_bond":
        return {"generator": "running_bond", "length": length, "height": height, "thickness": THICKNESS,
                "courses": courses, "per_course": per}
    if kind == "irregular":
        return {"generator": "irregular_wall", "length": length, "height": height, "thickness": THICKNESS,
                "courses": courses, "stone_length": [0.75 * STONE_LENGTH, 1.25 * STONE_LENGTH], "seed": seed,
                "name": f"irregular_{size}"}
    if kind == "polygonal":
        return {"generator": "polygonal_wall", "thickness": THICKNESS, "seed": seed, **POLYGONAL,
                **({"tiles": POLYGONAL_TILES[size]} if size in POLYGONAL_TILES else {})}
    raise ValueError(f"wall kind {kind!r}: one of {list(WALLS)}")


def build_wall(geometry: dict) -> dict:
    """The block-file dict of a case geometry table (``drystone.geometry.generators``); a
    table with ``tiles`` = k: the generator's wall laid k times along x (``tiled``)."""
    from drystone.geometry import generators
    geometry = dict(geometry)
    k = geometry.pop("tiles", 1)
    data = generators.generate(geometry)
    return tiled(data, k) if k > 1 else data


def tiled(data: dict, k: int) -> dict:
    """A block-file dict of ``k`` copies of a wall's stones side by side along x (each
    shifted by the stones' length; the copies' end faces flat and touching), on its
    platform lengthened by the same; stone ids renumbered copy by copy."""
    import copy

    stones = [b for b in data["blocks"] if b["role"] != "platform"]
    pts = np.vstack([np.vstack(b.get("parts", [b.get("vertices")])) for b in stones])
    length = float(pts[:, 0].max() - pts[:, 0].min())
    step = 1 + max(b["id"] for b in data["blocks"])
    out = copy.deepcopy(data)
    for b in out["blocks"]:
        if b["role"] == "platform":
            top = max(v[0] for v in b["vertices"])
            b["vertices"] = [[v[0] + (k - 1) * length if v[0] == top else v[0], v[1], v[2]] for v in b["vertices"]]
    for c in range(1, k):
        for b in copy.deepcopy(stones):
            b["id"] += c * step
            def shift(vs):
                return [[v[0] + c * length, v[1], v[2]] for v in vs]
            if "vertices" in b:
                b["vertices"] = shift(b["vertices"])
            if "parts" in b:
                b["parts"] = [shift(p) for p in b["parts"]]
            out["blocks"].append(b)
    out["control_points"] = []
    out["name"] = f"{data.get('name', 'wall')}_x{k}"
    return out


def stone_count(data: dict) -> int:
    """Stones of a block-file dict: every block but the platform (the fixed first course
    included)."""
    return sum(1 for b in data["blocks"] if b["role"] != "platform")


def time_step(data: dict, safety: float | None = None) -> float:
    """The runner's time step for a block-file dict: safety x the critical step
    (``drystone.model.timestep``, damping the largest of the materials'), safety the case
    default."""
    from drystone.model import case as casemod
    from drystone.model import timestep

    if safety is None:
        safety = casemod.SECTIONS["time"]["safety"].default
    mats = data["materials"]
    damp = max(m["damping"] for m in mats.values())
    blocks = [{"id": b["id"], "role": b["role"], "material": b["material"],
               "vertices": b["vertices"] if "vertices" in b else [p for part in b["parts"] for p in part],
               **({"parts": b["parts"]} if "parts" in b else {})} for b in data["blocks"]]
    return safety * timestep.critical_step(blocks, {n: dict(m, damping=damp) for n, m in mats.items()})[0]


def scale_steps(steps: int, size: int) -> int:
    """Steps of a scale run: ``steps``, four times as many for walls of 40 stones or fewer
    (their step is ~50 times cheaper: a run of a few seconds, above the noise)."""
    return 4 * steps if size <= 40 else steps


def scale_wall(kind: str, size: int, workdir: Path, tag: str) -> tuple:
    """(geometry, the geometry a case reads, stones, dt s) of a scale wall: a tiled wall,
    which no generator draws, written to ``workdir/tag.json`` for the case to read."""
    geo = wall_geometry(kind, size)
    data = build_wall(geo)
    run_geo = geo
    if "tiles" in geo:
        from drystone.geometry import blockfile
        run_geo = str(blockfile.write(data, workdir / f"{tag}.json"))
    return geo, run_geo, stone_count(data), time_step(data)


#: the scale runs' gravity ramp, a fraction of the run (``scale_case``; ``transient`` replays it)
SCALE_RAMP = 0.2


def scale_case(geometry: dict, dt: float, steps: int) -> dict:
    """A gravity run of ``steps`` steps of ``dt`` (gravity ramped over the first
    ``SCALE_RAMP`` of it), recording 5 samples (the recording is not what is measured)."""
    duration = steps * dt
    return {"case": {"name": "bench_scale", "geometry": geometry},
            "stages": [{"type": "gravity", "duration": duration, "ramp": SCALE_RAMP * duration}],
            "output": {"interval": duration / 5}}


def growth_exponent(n, cost) -> float:
    """Least-squares slope of log(cost) on log(n): cost ~ n^slope (nan below two sizes)."""
    n, cost = np.asarray(n, float), np.asarray(cost, float)
    if len(n) < 2 or len(np.unique(n)) < 2:
        return math.nan
    return float(np.polyfit(np.log(n), np.log(cost), 1)[0])


def settled_configuration(run_dir: Path):
    """(Shapes, pos, rot, moving, owner) of a finished run's last recorded state, as
    ``contacts_of_shapes`` takes them (a shape per convex part, ``owner`` its block's row;
    pos, rot, moving per block): free blocks where the run left them, the others where
    they were."""
    from drystone.mechanics import overlap as ov
    from drystone.mechanics import rotations
    from drystone.geometry import polyhedron as ph

    spec = json.loads((run_dir / "spec.json").read_text())
    h = np.load(run_dir / "histories.npz")
    row = {int(b): k for k, b in enumerate(h["block_ids"])}
    local, owner, pos, rot, moving = [], [], [], [], []
    for i, b in enumerate(spec["blocks"]):
        parts = [np.asarray(p, float) for p in b.get("parts", [b["vertices"]])]
        k = row.get(b["id"])
        if k is None:
            c = ph.volume_centroid(parts[0])[1] if len(parts) == 1 else np.vstack(parts).mean(axis=0)
            pos.append(c)
            rot.append(np.eye(3))
        else:
            c = h["pos0"][k]
            pos.append(h["pos"][-1][k])
            rot.append(rotations.to_matrix(h["quat"][-1][k]) @ rotations.to_matrix(h["quat0"][k]).T)
        local += [p - c for p in parts]
        owner += [i] * len(parts)
        moving.append(k is not None)
    return ov.Shapes(local), np.array(pos), np.array(rot), np.array(moving), np.array(owner, np.int64)


def _interleaved_ms(fns, budget_s: float = 1.0, rounds: int = 6) -> list[float]:
    """Fastest ms per call of each of ``fns``, timed in ``rounds`` alternating rounds of
    ~budget_s / (rounds len(fns)) each (a round's mean over its calls): what the machine's
    other load does to one it does to the others (two variants compared in one run, not one
    after the other)."""
    for fn in fns:
        fn()  # compiled / loaded from numba's cache
    best = [math.inf] * len(fns)
    for _ in range(rounds):
        for i, fn in enumerate(fns):
            t0, k = time.perf_counter(), 0
            while True:
                fn()
                k += 1
                dt = time.perf_counter() - t0
                if dt > budget_s / (rounds * len(fns)):
                    break
            best[i] = min(best[i], dt / k)
    return [1e3 * b for b in best]


def _best_ms(fn, budget_s: float = 1.0, repeats: int = 3) -> float:
    """Fastest of ``repeats`` means over ~budget_s / repeats of calls (ms): the least
    disturbed by other jobs."""
    return _interleaved_ms([fn], budget_s, repeats)[0]


#: steps per call of ``CompiledStep.advance`` in ``step_times``'s threads figure
ADVANCE_STEPS = 10


def contact_search_times(run_dir: Path, budget_s: float = 1.0) -> dict:
    """ms per call of the contact search on a run's settled positions, outside YADE:
    total, global geometry, broad phase (sort and sweep), exact clip of the candidates,
    and the former all-pairs search."""
    from drystone.mechanics import overlap as ov

    s, pos, rot, moving, owner = settled_configuration(run_dir)
    pos_s, rot_s, moving_s = pos[owner], rot[owner], moving[owner]  # per shape
    args = (s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, owner, pos, rot, moving, ov.TOL)
    GV, GN, GD, lo, hi = ov._global_geometry(s.verts, s.nv, s.normals, s.offsets, s.nf, pos_s, rot_s)
    ia, ib = ov.sweep_pairs(lo, hi, moving_s)
    keep = owner[ia] != owner[ib]  # a stone's parts are no pair
    ia, ib = ia[keep], ib[keep]
    out = ov.contacts_of_shapes(*args)
    r = {"bodies": int(len(pos)), "shapes": int(len(s.nv)), "candidates": int(len(ia)), "contacts": int(len(out[0])),
         "search_ms": _best_ms(lambda: ov.contacts_of_shapes(*args), budget_s),
         "geometry_ms": _best_ms(lambda: ov._global_geometry(s.verts, s.nv, s.normals, s.offsets, s.nf, pos_s, rot_s),
                                 budget_s / 4),
         "broad_phase_ms": _best_ms(lambda: ov.sweep_pairs(lo, hi, moving_s), budget_s / 4),
         "clip_ms": _best_ms(lambda: ov._contacts_of_pairs(GV, GN, GD, s.nv, s.nf, s.faces, s.fk, ia, ib, ov.TOL,
                                                           ov.TOUCHING_IS_NO_CONTACT), budget_s)}
    if len(pos) == len(s.nv):  # the former all-pairs search knows no parts
        r["all_pairs_ms"] = _best_ms(lambda: ov._contacts_all_pairs(*args[:7] + args[8:]), budget_s)
    return r


#: the step's phases ``step_phases`` times, in the order ``contact_step._advance`` runs them
PHASES = ("placement", "search", "law", "damping", "sums")


def step_phases(step, pos, rot, vel, angvel, dt, budget_s: float = 1.0) -> dict:
    """ms per call of each phase of one contact step (``contact_step._advance``),
    each kernel called from Python on ``step``'s state (a ``CompiledStep`` after a call of
    ``forces`` on that state: its contacts' history and damping bases warm, as in a
    settled run), one thread: the shapes' placement and the neighbour list's check
    (``neighbours.update``), the search (the listed pairs' box test and the clip of those
    that pass, ``neighbours.search``), the law (``contact_rows.law_rows``), the damping
    (``contact.damping_wrenches_warm``, the bases copied first: each call starts from the
    same ones) and the sums on the bodies (``contact_rows.body_sums``); ``contacts``: the
    contacts found. Where a contact-step's time goes; their sum is near ``forces``. Each call
    from Python includes numba's typing of its arguments (the search's two tuples: ~0.4 ms) and
    boxing of its results: the sum is above the step ``advance`` takes (docs/physics.md)."""
    from drystone.mechanics import contact as law
    from drystone.mechanics import contact_rows as crows
    from drystone.mechanics import contact_step as cs
    from drystone.mechanics import neighbours as nbr
    from drystone.mechanics import overlap as ov

    s, nl, buf = step.shapes, step.neighbours.arrays, step.neighbours.contacts
    nl = nbr.update(nl, s.verts, s.nv, s.normals, s.offsets, s.nf, step.owner, pos, rot, 1)
    m, buf = nbr.search(nl, buf, s.nv, s.nf, s.faces, s.fk, ov.TOL, bool(ov.TOUCHING_IS_NO_CONTACT))
    ia, ib, vol, c, n, area, pc, pj = (np.array(buf[k][:m]) for k in range(8))
    oa, ob = step.owner[ia], step.owner[ib]
    prev = cs._previous(ia * len(s.nv) + ib, step.keys)
    rows = (np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty((m, step.shear_store.shape[1])),
            np.empty((m, 6, 6)), np.empty(m), np.empty(m, np.bool_), np.empty((m, 3)), np.empty((m, 3)),
            np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 6)), np.empty((m, 3, 3)),
            np.empty((m, 3, 3)), np.empty((m, 4)))
    kn, kt, mu, xi, fn, fs, basis, jp, slipping, ra, rb, pa, pb, lever, twist, iia, iib, slip_terms = rows

    def law_rows():
        crows.law_rows(oa, ob, c, n, area, pc, pj, vol, pos, vel, angvel, rot, step.inv_inertia_local, step.material,
                       step.table, step.jkeys, step.jvals, prev, step.shear_store, step.basis_store, dt, *rows, 1)

    law_rows()
    ima, imb = step.inv_mass[oa], step.inv_mass[ob]

    def damping():
        return law.damping_wrenches_warm(n, area, pj, kn, kt, xi, ~slipping, pa, pb, ima, imb, iia, iib, twist, fn,
                                         fs, mu, lever, basis.copy(), prev >= 0, 1)

    fd, md, _ = damping()
    fns = {"placement": lambda: nbr.update(nl, s.verts, s.nv, s.normals, s.offsets, s.nf, step.owner, pos, rot, 1),
           "search": lambda: nbr.search(nl, buf, s.nv, s.nf, s.faces, s.fk, ov.TOL, bool(ov.TOUCHING_IS_NO_CONTACT)),
           "law": law_rows, "damping": damping,
           "sums": lambda: crows.body_sums(oa, ob, len(pos), fs, fn, n, fd, md, ra, rb, pa, pb, 1)}
    out = {k: _best_ms(fns[k], budget_s / len(PHASES)) for k in PHASES}
    out["contacts"] = int(m)
    return out


def compiled_step_of(run_dir: Path, s, moving, owner, threads: int = 1):
    """(CompiledStep, mass (nb,) kg, principal moments (nb, 3) kg m^2, the material table) for
    a finished run's blocks (``settled_configuration``'s shapes ``s``, ``moving``, ``owner``):
    masses the run's (histories.npz); principal moments those of each block's box in its body
    frame, materials the spec's first (the cost does not depend on their values)."""
    from drystone.mechanics import contact as law
    from drystone.mechanics import contact_step as cs

    spec = json.loads((run_dir / "spec.json").read_text())
    h = np.load(run_dir / "histories.npz")
    row = {int(b): k for k, b in enumerate(h["block_ids"])}
    nb = len(moving)
    mass = np.array([h["mass"][row[b["id"]]] if b["id"] in row else np.inf for b in spec["blocks"]], float)
    ext = np.array([np.ptp(np.asarray(b["vertices"], float), axis=0) for b in spec["blocks"]])
    box = np.stack([ext[:, 1] ** 2 + ext[:, 2] ** 2, ext[:, 0] ** 2 + ext[:, 2] ** 2, ext[:, 0] ** 2 + ext[:, 1] ** 2], 1)
    inertia = np.where(moving[:, None], np.where(moving, mass, 1.0)[:, None] / 12.0 * box, 1.0)
    mat = next(iter(spec["materials"].values()))
    props = law.pair_properties(mat, mat)
    table = np.array([[[props[k] for k in ("kn", "kt", "mu", "damping")]]])
    step = cs.CompiledStep(mass, inertia, [s.verts[i, :s.nv[i]] for i in range(len(s.nv))], np.zeros(nb, int), table,
                           owner=owner, threads=threads)
    return step, mass, inertia, table


def transient(run_dir: Path):
    """A callable that replays a scale run's steps outside YADE (``CompiledStep.advance``, one
    call): from its blocks' starting positions at rest, under gravity ramped over the first
    fifth of the run as ``scale_case`` ramps it, the run's dt and number of steps. The stones
    settle, contacts form, stick and slip: the step as a run pays for it, where ``step_times``
    takes the settled state. The step's kernels are loaded (compiled) when this returns."""
    s, pos, rot, moving, owner = settled_configuration(run_dir)
    spec = json.loads((run_dir / "spec.json").read_text())
    h = np.load(run_dir / "histories.npz")
    row = {int(b): k for k, b in enumerate(h["block_ids"])}
    for i, b in enumerate(spec["blocks"]):  # the free blocks where the run started them
        k = row.get(b["id"])
        if k is not None:
            pos[i] = h["pos0"][k]
            rot[i] = np.eye(3)
    step, mass, inertia, _ = compiled_step_of(run_dir, s, moving, owner)
    nb, dt = len(pos), float(spec["dt"])
    n = int(json.loads((run_dir / "run_info.json").read_text())["steps"])
    vel, w = np.zeros((nb, 3)), np.zeros((nb, 3))
    free = np.where(moving[:, None], 1.0, 0.0) * np.ones((nb, 3))
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (nb, 1))
    motion = (np.where(moving, mass, 1.0), inertia, free, free, moving.copy(), np.zeros((nb, 3)), quat)
    t = dt * np.arange(1, n + 1)
    g = np.zeros((n, 3))
    g[:, 2] = -units.GRAVITY * np.minimum(1.0, t / (SCALE_RAMP * n * dt))
    step.forces(pos, rot, vel, w, dt)  # the kernels loaded before anything is timed

    def run():
        done, _, _, ok = step.advance(pos, rot, vel, w, dt, g, np.zeros((nb, 3)), motion)
        return {"steps": int(done), "contacts": int(len(step.keys)), "completed": bool(ok)}
    return run


def profile_section(workdir: Path, sizes=(500,), walls=("running_bond", "polygonal"), steps: int = 300) -> dict:
    """Section profile: each scale wall's run replayed outside YADE (``transient``) under
    ``perf`` (``drystone.kernel_profile``): the share of the step of each kernel and each
    phase, sampled inside the compiled loop. Skipped, saying why, where perf is missing."""
    from drystone import kernel_profile as kprof

    print("\nprofile: the scale walls' runs replayed in one compiled call, sampled by perf:", flush=True)
    why = kprof.available()
    if why:
        print(f"  skipped: {why}", flush=True)
        return {"skipped": why}
    rows = []
    for kind in walls:
        for size in [n for n in sizes if n in WALL_SIZES.get(kind, sizes)]:
            tag = f"profile_{kind}_{size}"
            _, run_geo, n, dt = scale_wall(kind, size, workdir, tag)
            runner.run_dict(scale_case(run_geo, dt, scale_steps(steps, size)), workdir / f"{tag}.toml",
                            out_dir=workdir / tag, quiet=True,
                            overrides=["contact.law=penalty_coulomb", "contact.detection=native"])
            p = kprof.profile(transient(workdir / tag))
            r = p.pop("result")
            row = dict(wall=kind, size=size, stones=n, ms_per_step=1e3 * p["samples_s"] / r["steps"],
                       **r, **p)
            rows.append(row)
            print(f"  {kind:12s} {size:5d} stones: {row['ms_per_step']:.2f} ms/step over {r['steps']} steps "
                  f"({r['contacts']} contacts at the end); % of the samples:", flush=True)
            print("    " + ", ".join(f"{k} {v:.1f}" for k, v in p["phases"].items() if v >= 0.05), flush=True)
            print("    " + ", ".join(f"{k} {v:.1f}" for k, v in list(p["kernels"].items())[:8]), flush=True)
    return {"rows": rows, "steps": steps}


def step_times(run_dir: Path, budget_s: float = 1.0) -> dict:
    """ms per call, outside YADE, on a run's settled positions (``settled_configuration``),
    of the compiled step's two halves: the contact forces (``CompiledStep.forces``: search,
    law and damping, each contact's history from the call before) and the integration of
    every body (``integration.integrate``, Fincham's scheme for the free blocks); the
    forces and the whole step as a run takes it (``CompiledStep.advance``, ADVANCE_STEPS
    steps under gravity per call) on 1 and 2 threads, timed in alternating rounds
    (``_interleaved_ms``), and their parallel efficiencies t1 / (2 t2); the contact
    step's phases on one thread (``step_phases``: ``phases_ms``). Masses
    are the run's (histories.npz); principal moments those of each block's box in its body
    frame, materials the spec's first (the cost does not depend on their values)."""
    from scipy.spatial.transform import Rotation

    from drystone.mechanics import integration

    s, pos, rot, moving, owner = settled_configuration(run_dir)
    step, mass, inertia, _ = compiled_step_of(run_dir, s, moving, owner)
    spec = json.loads((run_dir / "spec.json").read_text())
    nb = len(pos)
    vel, w, dt = np.zeros((nb, 3)), np.zeros((nb, 3)), float(spec["dt"])
    F, T = step.forces(pos, rot, vel, w, dt)
    free = np.where(moving[:, None], 1.0, 0.0) * np.ones((nb, 3))
    m_int = np.where(moving, mass, 1.0)
    state = [pos.copy(), vel.copy(), w.copy(), np.zeros((nb, 3)), np.tile([0.0, 0.0, 0.0, 1.0], (nb, 1)), rot.copy()]
    step2 = compiled_step_of(run_dir, s, moving, owner, threads=2)[0]
    t1, t2 = _interleaved_ms([lambda: step.forces(pos, rot, vel, w, dt), lambda: step2.forces(pos, rot, vel, w, dt)],
                             budget_s, rounds=20)
    # what a run calls: ``advance`` (ADVANCE_STEPS steps under gravity), each thread count on its own copy of the state
    quat = Rotation.from_matrix(rot).as_quat()  # (x, y, z, w), as the package's
    copies = [[pos.copy(), rot.copy(), vel.copy(), w.copy(), (m_int, inertia, free, free, moving.copy(),
                                                             np.zeros((nb, 3)), quat.copy())] for _ in range(2)]
    g = np.tile([0.0, 0.0, -9.81], (ADVANCE_STEPS, 1))

    def advance(st, c):
        return lambda: st.advance(c[0], c[1], c[2], c[3], dt, g, np.zeros((nb, 3)), c[4])

    a1, a2 = (ms / ADVANCE_STEPS for ms in _interleaved_ms([advance(step, copies[0]), advance(step2, copies[1])],
                                                           budget_s, rounds=20))
    step.forces(pos, rot, vel, w, dt)  # the history of the settled state again (``advance`` moved its copy)
    phases = step_phases(step, pos, rot, vel, w, dt, budget_s)
    return {"contacts": int(len(step.keys)), "forces_ms": t1, "forces_ms_2_threads": t2,
            "forces_efficiency": t1 / (2.0 * t2), "threads_available": step2.threads,
            "advance_ms_per_step": a1, "advance_ms_per_step_2_threads": a2, "advance_efficiency": a1 / (2.0 * a2),
            "phases_ms": phases,
            "integrate_ms": _best_ms(lambda: integration.integrate(dt, np.zeros(3), F, T, m_int, inertia, free, free,
                                                          moving.copy(), *state, 1), budget_s / 2)}


def scale_series(rows: list[dict]) -> dict:
    """The scale rows that did not fail by series (a wall, and its engine where the rows have
    several), each in increasing stone count."""
    several = len({r["engine"] for r in rows}) > 1
    out: dict = {}  # the series in the rows' order
    for r in rows:
        if "failed" not in r:
            out.setdefault(f"{r['wall']}/{r['engine']}" if several else r["wall"], []).append(r)
    return {k: sorted(v, key=lambda r: r["stones"]) for k, v in out.items()}


def scale_fits(rows: list[dict]) -> tuple[dict, dict]:
    """(cost growth exponent of ms/step over the stones, KiB per further stone) of each
    series of scale rows (``scale_series``) with two sizes or more."""
    fits, marginal = {}, {}
    for key, series in scale_series(rows).items():
        if len(series) < 2:
            continue
        fits[key] = growth_exponent([r["stones"] for r in series], [r["ms_per_step"] for r in series])
        mem = [(r["stones"], r["max_rss_mib"]) for r in series if r.get("max_rss_mib")]
        if len(mem) >= 2 and mem[-1][0] > mem[0][0]:  # the memory each further stone takes
            marginal[key] = 1024.0 * (mem[-1][1] - mem[0][1]) / (mem[-1][0] - mem[0][0])
    return fits, marginal


def merge_scale(old: dict | None, new: dict) -> dict:
    """The scale section of bench.json after a run of some walls and sizes (``new``): its rows
    replace the earlier rows of the same wall, engine and size, the others stay (each row
    says when it was measured); the fits are made again over the rows kept."""
    if not old or not old.get("rows"):
        return new
    key = lambda r: (r["wall"], r["engine"], r["size"])  # noqa: E731
    fresh = {key(r): r for r in new["rows"]}
    rows = [fresh.pop(key(r), r) for r in old["rows"]] + list(fresh.values())
    fits, marginal = scale_fits(rows)
    return dict(new, rows=rows, growth_exponent=fits, kib_per_further_stone=marginal)


def scale_section(workdir: Path, sizes=SIZES, walls=WALLS, steps: int = 300, engines=None) -> dict:
    """Section b: each wall under gravity for ``steps`` steps (our law, native geometry,
    one thread; each of ``engines``, default the runner's), then its contact search alone
    on the settled positions."""
    if engines and not engine_supported():
        print("  compiled step not available (runner.run_dict takes no 'engine'): the runner's only step", flush=True)
        engines = None
    engines = list(engines) if engines else [None]
    print(f"\nscale: walls under gravity, {steps} steps each ({scale_steps(steps, 40)} for 40 stones; penalty_coulomb, "
          "native geometry, 1 thread):", flush=True)
    rows = []
    for kind, engine in [(k, e) for k in walls for e in engines]:
        for size in [n for n in sizes if n in WALL_SIZES.get(kind, sizes)]:
            tag = f"scale_{kind}_{size}" + (f"_{engine}" if engine else "")
            geo, run_geo, n, dt = scale_wall(kind, size, workdir, tag)
            try:
                r = timed_run(scale_case(run_geo, dt, scale_steps(steps, size)), workdir, tag, 1,
                              ["contact.law=penalty_coulomb", "contact.detection=native"], engine,
                              wall=kind, engine=engine or "default", size=size, stones=n, geometry=geo)
            except runner.RunError as exc:  # one wall's failure leaves the others' figures
                rows.append({"wall": kind, "engine": engine or "default", "size": size, "stones": n,
                             "geometry": geo, "failed": str(exc)})
                print(f"  {kind:12s} {engine or 'default':8s} {n:5d} stones: FAILED: {exc}", flush=True)
                continue
            r["us_per_contact_step"] = 1e3 * r["ms_per_step"] / max(1, r["final_contacts"] or r["contacts"])
            if r.get("max_rss_mib"):  # the YADE process's peak memory over the stones (KiB each)
                r["kib_per_stone"] = 1024.0 * r["max_rss_mib"] / n
            run_dir = Path(r.pop("out"))
            r["search"] = contact_search_times(run_dir)
            r["split"] = step_times(run_dir)
            # the step on the settled wall outside YADE, alternating with 2 threads: less disturbed by other jobs
            r["advance_us_per_contact_step"] = 1e3 * r["split"]["advance_ms_per_step"] / max(1, r["split"]["contacts"])
            if size in THREADED_SIZES:  # the same run on 2 threads
                try:
                    r2 = timed_run(scale_case(run_geo, dt, scale_steps(steps, size)), workdir, tag + "_2", 2,
                                   ["contact.law=penalty_coulomb", "contact.detection=native"], engine)
                    r["ms_per_step_2_threads"] = r2["ms_per_step"]
                    r["parallel_efficiency"] = r["ms_per_step"] / (2.0 * r2["ms_per_step"])
                except runner.RunError as exc:
                    r["threads_failed"] = str(exc)
            r["search_share"] = r["search"]["search_ms"] / r["ms_per_step"]
            r["broad_phase_share"] = (r["search"]["geometry_ms"] + r["search"]["broad_phase_ms"]) / r["ms_per_step"]
            rows.append(r)
            sr = r["search"]
            print(f"  {kind:12s} {r['engine']:8s} {n:5d} stones: {r['ms_per_step']:8.2f} ms/step  "
                  f"{r['final_contacts']:5d} contacts  {r['us_per_contact_step']:6.2f} us/contact-step  "
                  f"(dt {dt:.2e} s; whole run {r['ms_per_step_run']:.2f} ms/step, start-up {r['startup_s']:.1f} s)"
                  f"{DISTURBED if r['disturbed'] else ''}\n"
                  f"  {'':21s} contact search alone {sr['search_ms']:.2f} ms ({100 * r['search_share']:.0f} % of the "
                  f"step): broad phase {sr['geometry_ms'] + sr['broad_phase_ms']:.3f} ms "
                  f"({100 * r['broad_phase_share']:.1f} %), clip of {sr['candidates']} candidates "
                  f"{sr['clip_ms']:.2f} ms" + (f"; the former all-pairs search {sr['all_pairs_ms']:.2f} ms" if "all_pairs_ms" in sr else "") + "\n"
                  f"  {'':21s} step in two halves alone: contact forces (search, law, damping) "
                  f"{r['split']['forces_ms']:.3f} ms, integration of {n} stones {r['split']['integrate_ms']:.3f} ms; "
                  f"the whole step as a run calls it (advance, fastest of 20 rounds) {r['split']['advance_ms_per_step']:.3f} ms, "
                  f"{r['advance_us_per_contact_step']:.2f} us/contact-step"
                  + (f"\n  {'':21s} its phases alone, us per contact: " + ", ".join(
                      f"{k} {1e3 * r['split']['phases_ms'][k] / max(1, r['split']['phases_ms']['contacts']):.2f}"
                      for k in PHASES) if "phases_ms" in r["split"] else "")
                  + (f"\n  {'':21s} 2 threads: {r['ms_per_step_2_threads']:.2f} ms/step, parallel efficiency t1/(2 t2) "
                     f"{r['parallel_efficiency']:.2f} (the runs, one after the other); alternating with 1 thread: "
                     f"advance {r['split']['advance_ms_per_step']:.3f} -> {r['split']['advance_ms_per_step_2_threads']:.3f} "
                     f"ms/step (efficiency {r['split']['advance_efficiency']:.2f}), contact forces alone "
                     f"{r['split']['forces_ms']:.3f} -> {r['split']['forces_ms_2_threads']:.3f} ms (efficiency "
                     f"{r['split']['forces_efficiency']:.2f}: with the elastic energy of every call, on one thread)"
                     if "parallel_efficiency" in r else "")
                  + (f"\n  {'':21s} memory: peak {r['max_rss_mib']:.0f} MiB, {r['kib_per_stone']:.0f} KiB per stone"
                     if "kib_per_stone" in r else ""), flush=True)
    measured = time.strftime("%Y-%m-%dT%H:%M:%S%z")  # a row kept by a later partial run says when it was made
    for r in rows:
        r["measured"] = measured
    fits, marginal = scale_fits(rows)
    series = scale_series(rows)
    for key, slope in fits.items():
        extra = f"; memory {marginal[key]:.0f} KiB per further stone" if key in marginal else ""
        print(f"  {key}: cost ~ N^{slope:.2f} over N = {', '.join(str(r['stones']) for r in series[key])}{extra}",
              flush=True)
    return {"steps": steps, "rows": rows, "growth_exponent": fits, "kib_per_further_stone": marginal}


# -- c: threads with a second run going -------------------------------------------------------

def recommend_threads(rows: list[dict], margin: float = 0.1) -> tuple[int, str]:
    """The default thread count the measurements suggest: 2 only if 2 threads beat 1 by
    more than ``margin`` both alone and with a second run going (``rows``: dicts with
    threads, second_run (bool) and ms_per_step); else 1 (and, on a shared machine, as
    many parallel runs as cores)."""
    ms = {(r["threads"], r["second_run"]): r["ms_per_step"] for r in rows}
    alone = ms.get((1, False), math.nan) / ms.get((2, False), math.nan)
    loaded = ms.get((1, True), math.nan) / ms.get((2, True), math.nan)
    why = f"2 threads run {alone:.2f}x the speed of 1 alone and {loaded:.2f}x with a second run going"
    if alone > 1 + margin and loaded > 1 + margin:
        return 2, why
    return 1, why + f" (not above {1 + margin:.1f}x in both): one thread per run, one run per core"


def _wait_stepping(log: Path, proc: subprocess.Popen, timeout: float = 180.0) -> None:
    t0 = time.time()
    while time.time() - t0 < timeout:
        if proc.poll() is not None:
            raise RuntimeError(f"the background run ended early (exit {proc.returncode})")
        if log.is_file() and "stage 1/" in log.read_text(errors="replace"):
            return
        time.sleep(0.5)
    raise RuntimeError("the background run did not start stepping")


def _stop(proc: subprocess.Popen) -> None:
    """Stop the background run started here: SIGTERM (the command line then kills its
    YADE and exits), SIGKILL if it hangs."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def threads_section(workdir: Path) -> dict:
    """Section c: the 40-block wall (the case defaults: our law, its default geometry and
    step) on 1 and 2 threads, alone and while a second identical but longer run (one
    thread) is going in a background process started here and stopped after."""
    from drystone.tomlio import to_toml

    case = dict(CASE, case={"name": "bench_threads", "geometry": {"generator": "running_bond"}})
    print("\nthreads: 40-block wall (case defaults), alone and with a second run going:", flush=True)
    rows = []
    for second in (False, True):
        proc = None
        if second:
            p = workdir / "background.toml"
            p.write_text(to_toml(dict(case, stages=[{"type": "gravity", "duration": 60.0, "ramp": 0.2}],
                                      output={"interval": 0.5})))
            bg_out = workdir / "background"
            with open(workdir / "background.log", "w") as log:
                proc = subprocess.Popen([sys.executable, "-m", "drystone", "run", str(p), "--out", str(bg_out),
                                         "-j", "1", "-q"], stdout=log, stderr=subprocess.STDOUT, cwd=paths.ROOT)
        try:
            if proc is not None:
                _wait_stepping(bg_out.parent / f".{bg_out.name}.partial" / "log.txt", proc)
            for threads in (1, 2):
                tag = f"threads_{threads}_{'second' if second else 'alone'}"
                rows.append(timed_run(case, workdir, tag, threads, second_run=second))
                del rows[-1]["out"]
                if proc is not None and proc.poll() is not None:
                    raise RuntimeError("the background run ended before the measurement did")
                print(f"  {threads} thread(s), {'with a second run going' if second else 'alone':24s}: "
                      f"{rows[-1]['ms_per_step']:7.2f} ms/step (whole run {rows[-1]['ms_per_step_run']:.2f})"
                      f"{DISTURBED if rows[-1]['disturbed'] else ''}", flush=True)
        finally:
            if proc is not None:
                _stop(proc)
    n, why = recommend_threads(rows)
    print(f"  recommendation: default -j {n}: {why}", flush=True)
    return {"rows": rows, "recommended_threads": n, "why": why}


# -- d: Sacsayhuaman analyses vs Abaqus ------------------------------------------------------

#: the Sacsayhuaman paper's Abaqus/Explicit run times on 8 cores (data/papers/sacsayhuaman.toml)
ANALYSES = (("white noise 30 s", "white_noise_30s", "sacsayhuaman_white_noise", 30.0),
            ("sine 10 s", "sine_10s", "sacsayhuaman_sine", 10.0),
            ("Paruro 60 s", "paruro_60s", "paruro2014", None),
            ("Cusco", "cusco", "cusco2023", None),
            ("Ancash", "ancash", "ancash1970", None))


def sacsayhuaman_times(workdir: Path) -> list[dict]:
    """Wall time per analysis of the 40-stone section on one core: start-up plus the
    analysis's steps (gravity 2 s + the motion; a sine also has 2 s of rest, a record 2 s)
    at the ms/step of a short white-noise run, beside the paper's Abaqus times on 8 cores
    (ratio ours / Abaqus, its inverse the speed-up, and the ratio of core-seconds), and the
    times of finished study runs where there are some. The case leaves the contact
    geometry and step to their defaults, as the study's cases do."""
    from drystone.motions import catalogue
    from drystone.postprocess import compare

    case = {"case": {"name": "bench_sacsayhuaman", "geometry": {"generator": "sacsayhuaman", "seed": 0}},
            "stages": [{"type": "gravity", "duration": 0.5, "ramp": 0.25},
                       {"type": "excitation", "motion": "white_noise", "duration": 1.5, "direction": "y"}],
            "output": {"interval": 0.01}}
    t = timed_run(case, workdir, "sacs")
    ms, dt, startup = t["ms_per_step"], t["dt_s"], max(0.0, t["startup_s"])
    detection = json.loads((Path(t.pop("out")) / "spec.json").read_text())["detection"]
    abaqus = compare.paper("sacsayhuaman")["run_times_s"]
    rows = []
    for label, key, source, dur in ANALYSES:
        if dur is None:
            dur = catalogue.get(source).duration
            if source == "paruro2014":
                dur = min(dur, 60.0)
        sim = 2.0 + dur + (2.0 if key != "white_noise_30s" else 0.0)
        est = startup + sim / dt * ms / 1e3
        actual = _actual_wall_times(source)
        rows.append({"analysis": label, "simulated_s": sim, "estimated_wall_s": est, "abaqus_8_cores_s": abaqus[key],
                     "ratio_to_abaqus": est / abaqus[key], "speedup_vs_abaqus": abaqus[key] / est,
                     "core_seconds_ratio": est / (8 * abaqus[key]), "ms_per_step": ms,
                     "ms_per_step_run": t["ms_per_step_run"], "startup_s": startup, "dt_s": dt,
                     "detection": detection, "engine": t["engine_used"] or "default", "study_runs_wall_s": actual})
    return rows


def _actual_wall_times(source: str) -> list[float]:
    """Wall times (s) of finished study runs of this analysis, if any."""
    import glob
    if source.startswith("sacsayhuaman_"):
        pattern = str(paths.RESULTS / source / "*" / "summary.json")
    else:
        pattern = str(paths.RESULTS / "sacsayhuaman_table3" / f"record_{source}-*" / "summary.json")
    return [json.loads(Path(p).read_text())["run"]["wall_time_s"] for p in sorted(glob.glob(pattern))]


def print_sacsayhuaman(sacs: list[dict]) -> None:
    r0 = sacs[0]
    print(f"\nSacsayhuaman section, one core, {r0['detection']} contacts ({r0['ms_per_step']:.2f} ms/step), "
          "against the paper's Abaqus/Explicit on 8 cores:")
    print(f"  {'analysis':17s} {'simulated':>9s} {'ours':>8s} {'Abaqus':>8s} {'ours/Abaqus':>11s} {'speed-up':>8s}")
    for r in sacs:
        done = (f"  study runs: {min(r['study_runs_wall_s']):.0f}-{max(r['study_runs_wall_s']):.0f} s"
                if r["study_runs_wall_s"] else "")
        print(f"  {r['analysis']:17s} {r['simulated_s']:7.1f} s {r['estimated_wall_s']:6.0f} s "
              f"{r['abaqus_8_cores_s'] / 60:4.0f} min {r['ratio_to_abaqus']:11.4f} {r['speedup_vs_abaqus']:7.1f}x"
              f"{done}", flush=True)


# -- e: compilation on a cold cache ----------------------------------------------------------

def compile_section(workdir: Path) -> dict:
    """The ``compile`` section (module docstring): one ``python -m drystone run`` of the
    40-block wall's ``warm_case`` (several steps in one compiled call, as a run's) on an
    empty numba cache of its own (``NUMBA_CACHE_DIR``), then one more on what it wrote."""
    from drystone.tomlio import to_toml

    dt = time_step(build_wall(CASE["case"]["geometry"]))
    case_path = workdir / "compile.toml"
    atomic.write_text(case_path, to_toml(warm_case(CASE, dt)))
    cache = workdir / "numba_cache_cold"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    out: dict = {}
    print("\ncompile: the 40-block wall's first steps on an empty numba cache, then on the one it wrote:", flush=True)
    for tag in ("cold", "warm"):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "drystone", "run", str(case_path), "--out", str(workdir / f"compile_{tag}"),
                        "-q", "--set", "contact.law=penalty_coulomb", "--set", "contact.detection=native"], env=env,
                       check=True, capture_output=True)
        out[f"{tag}_s"] = time.perf_counter() - t0
    out["compile_s"] = out["cold_s"] - out["warm_s"]
    out["overloads"] = len(list(cache.rglob("*.nbc")))
    print(f"  {out['cold_s']:.1f} s on the empty cache, {out['warm_s']:.1f} s on the full one: {out['compile_s']:.1f} s "
          f"compiling {out['overloads']} overloads", flush=True)
    return out


# -- main ----------------------------------------------------------------------------------

def write_results(results: dict, path: Path | None = None) -> Path:
    """Merge ``results`` (sections of this run) into bench.json: sections not run this time
    keep their earlier figures (each section carries its machine facts), and the scale
    section its rows of the walls and sizes not run (``merge_scale``)."""
    path = path or paths.RESULTS / "bench" / "bench.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    old = {}
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except json.JSONDecodeError:
            old = {}
    if "scale" in results:  # a run of some walls or sizes keeps the others' rows
        results = dict(results, scale=merge_scale(old.get("scale"), results["scale"]))
    old.update(results)
    return atomic.write_text(path, json.dumps(old, indent=1))


#: the limit section's large wall: running bond, 40 courses of 25 stones (1000, the first course
#: fixed), STONE_LENGTH x COURSE_HEIGHT x THICKNESS stones
LIMIT_WALL = {"generator": "running_bond", "length": 25 * STONE_LENGTH, "height": 40 * COURSE_HEIGHT,
              "thickness": THICKNESS, "courses": 40, "per_course": 25}
#: the speed goals of the limit analysis (CPU s of one process: geometry + interfaces + associative LP)
LIMIT_GOALS_S = {"sacsayhuaman": 1.0, "running_bond_1000": 10.0}


def limit_section() -> list[dict]:
    """Times of the limit analysis (module docstring, section ``limit``)."""
    from drystone.analyses import limit as lim
    from drystone.geometry import blockfile as bf
    from drystone.mechanics import limit_analysis as la
    from drystone.model import case as casemod
    from drystone.model import resolve

    rows = []
    for name in LIMIT_GOALS_S:
        t0, c0 = time.perf_counter(), time.process_time()
        if name == "sacsayhuaman":
            path = paths.ROOT / "cases" / "sacsayhuaman" / "sine.toml"
            case = casemod.load(path)
            with tempfile.TemporaryDirectory() as tmp:
                bs, _ = resolve._geometry(case, str(path), Path(tmp))
            mats = resolve._materials(case, bs, str(path))
        else:
            bs = bf.parse(build_wall(LIMIT_WALL), name, check_overlaps=False)
            mats = {n: {k: getattr(m, k) for k in bf.MATERIAL_PROPERTIES} for n, m in bs.materials.items()}
        t1 = time.perf_counter()
        wall = lim.wall_of(bs, mats, 9.81, name)
        t2 = time.perf_counter()
        c2 = time.process_time()
        r = la.solve(wall.bodies, wall.ifaces, wall.mu, (0.0, 1.0, 0.0))
        t3, c3 = time.perf_counter(), time.process_time()
        row = {"wall": name, "stones": int((~wall.bodies.fixed).sum()), "interfaces": len(wall.ifaces),
               "corners": int(sum(len(f.polygon) for f in wall.ifaces)), "geometry_s": t1 - t0,
               "interfaces_s": t2 - t1, "lp_s": t3 - t2, "total_s": t3 - t0, "lp_cpu_s": c3 - c2,
               "total_cpu_s": c3 - c0, "multiplier": r.multiplier,
               "status": r.status, "goal_s": LIMIT_GOALS_S[name]}
        # one core's CPU time: on a shared machine the wall time measures the other jobs too
        row["goal_met"] = row["total_cpu_s"] < row["goal_s"]
        if name == "sacsayhuaman":
            t4, c4 = time.perf_counter(), time.process_time()
            rc = la.solve_coulomb(wall.bodies, wall.ifaces, wall.mu, (0.0, 1.0, 0.0))
            row.update(coulomb_s=time.perf_counter() - t4, coulomb_cpu_s=time.process_time() - c4,
                       coulomb_multiplier=rc.multiplier, coulomb_status=rc.status,
                       coulomb_iterations=rc.iterations)
            print(f"  limit {name}: non-associative {rc.status} lambda {rc.multiplier} in {rc.iterations - 1} "
                  f"iterations, {row['coulomb_cpu_s']:.2f} CPU s", flush=True)
        print(f"  limit {name}: {row['stones']} stones, {row['interfaces']} interfaces; geometry "
              f"{row['geometry_s']:.2f} s, interfaces {row['interfaces_s']:.2f} s, LP {row['lp_s']:.2f} s, total "
              f"{row['total_s']:.2f} s, CPU {row['total_cpu_s']:.2f} s (goal < {row['goal_s']:g} s: "
              f"{'met' if row['goal_met'] else 'NOT met'}); "
              f"lambda {r.multiplier}", flush=True)
        rows.append(row)
    return rows


#: the fragility_ida section: its case, the goal for the 22 records on 2 workers (min), and its
#: default IDA settings (the bracket's width, g; the analysis's own default cap and start)
FRAGILITY_CASE = paths.ROOT / "cases" / "sacsayhuaman" / "record.toml"
FRAGILITY_GOAL_MIN = 60.0
FRAGILITY_RECORDS = 22
FRAGILITY_TOLERANCE = 0.1


def fragility_estimate(n_records: int, runs: int, run_wall_s: float, workers: int,
                       total_records: int = FRAGILITY_RECORDS) -> dict:
    """The whole set's cost from the records run: runs per record, seconds per run, and the
    wall time of ``total_records`` records on ``workers`` processes (each process busy all
    the time: runs / workers x seconds per run)."""
    per_record = runs / n_records
    per_run = run_wall_s / runs
    total_runs = per_record * total_records
    return {"runs_per_record": per_record, "s_per_run": per_run, "runs_all": total_runs,
            "core_min_all": total_runs * per_run / 60, "wall_min_all": total_runs * per_run / workers / 60,
            "extrapolated": n_records < total_records}


def fragility_section(n_records: int | None = None, tolerance: float = FRAGILITY_TOLERANCE,
                      duration_s: float | None = None, workers: int = 2) -> dict:
    """``fragility`` by IDA on the Sacsayhuaman record case (module docstring)."""
    from drystone.analyses import fragility as fr

    n = FRAGILITY_RECORDS if n_records is None else max(1, min(int(n_records), FRAGILITY_RECORDS))
    records = ["farfield"] if n == FRAGILITY_RECORDS else [f"fema:{i}a" for i in range(1, n + 1)]
    out = paths.RESULTS / "bench" / "fragility_ida"
    t0 = time.time()
    res = fr.fragility(FRAGILITY_CASE, records, method="ida", tolerance=tolerance, duration_s=duration_s,
                       workers=workers, out=out, n_boot=200)
    elapsed = time.time() - t0
    cost = res["cost"]
    runs = [x for r in res["records"].values() for x in r.get("runs", [])]
    sim = [x.get("end_time_s") for x in runs if x.get("end_time_s")]
    est = fragility_estimate(n, cost["runs"], cost["run_wall_s"], workers)
    st = res["states"]["collapse"]
    row = {"case": str(FRAGILITY_CASE), "records": n, "workers": workers, "tolerance_g": tolerance,
           "duration_s": duration_s, "runs": cost["runs"], "elapsed_s": elapsed,
           "run_wall_s": cost["run_wall_s"], "core_min": cost["run_wall_s"] / 60,
           "simulated_s_per_run": sum(sim) / len(sim) if sim else None,
           "wall_s_per_simulated_s": cost["run_wall_s"] / sum(sim) if sim else None,
           "theta_g": st.get("theta"), "beta": st.get("beta"), "fit": st.get("reason") or "fitted",
           "brackets": {k: r.get("pga_at_collapse_g") or r.get("censored_at_g") for k, r in res["records"].items()},
           "estimate": est, "goal_min": FRAGILITY_GOAL_MIN, "goal_met": est["wall_min_all"] <= FRAGILITY_GOAL_MIN,
           "out_dir": res["out_dir"]}
    word = "extrapolated from " + f"{n} record(s)" if est["extrapolated"] else "measured"
    print(f"  fragility_ida: {n} record(s), {cost['runs']} runs ({est['runs_per_record']:.1f} per record), "
          f"{elapsed / 60:.1f} min wall on {workers} workers, {row['core_min']:.1f} core-min "
          f"({est['s_per_run']:.0f} s per run" + (f", {row['simulated_s_per_run']:.1f} s simulated, "
                                                   f"{row['wall_s_per_simulated_s']:.1f} s per simulated s"
                                                   if sim else "") + "); "
          + (f"theta {st['theta']:.3g} g, beta {st['beta']:.3g}" if st.get("theta") is not None
             else f"no fit ({st.get('reason')})")
          + f"; all {FRAGILITY_RECORDS} records: {est['wall_min_all']:.0f} min on {workers} workers ({word}; "
          f"goal <= {FRAGILITY_GOAL_MIN:g} min: {'met' if row['goal_met'] else 'NOT met'})", flush=True)
    return row


def main(only=None, sizes=SIZES, walls=WALLS, steps: int = 300, engines=None, fragility: dict | None = None,
         baseline: str | None = None, rounds: int = 2) -> dict:
    """Run the sections ``only`` (default all, in SECTIONS' order; with ``baseline`` and no
    ``only``, that section alone) and write bench.json; ``fragility``: the fragility_ida
    section's options (``fragility_section``'s keywords); ``baseline``: a commit whose scale
    section is run back to back with this tree's in ``rounds`` rounds (``bench_baseline``)."""
    if baseline is not None:
        from drystone import bench_baseline
        bench_baseline.resolve(baseline)  # a name that is no commit stops here, before any run
    only = ([] if baseline is not None else list(SECTIONS)) if not only else [s for s in SECTIONS if s in only]
    sections = only + (["baseline"] if baseline is not None else [])
    facts = machine()
    print(f"machine: {facts['cores']} cores, load average {facts['load_average_at_start'][0]:.2f} at the start, "
          f"YADE {facts['yade_version']}; sections: {', '.join(sections)}", flush=True)
    results: dict = {}
    t0 = time.time()
    with tempfile.TemporaryDirectory(dir=paths.ROOT) as tmp:
        tmp = Path(tmp)
        if set(only) - {"limit", "fragility_ida", "compile"}:  # limit: no YADE; fragility primes; compile: a cold cache
            prime(tmp)
        if "running_bond" in only:
            results["running_bond"] = running_bond_section(tmp)
            results["running_bond_goal"] = goal(results["running_bond"])
            results["running_bond_machine"] = facts
        if "scale" in only:
            results["scale"] = dict(scale_section(tmp, sizes, walls, steps, engines), machine=facts)
        if "threads" in only:
            results["threads"] = dict(threads_section(tmp), machine=facts)
        if "sacsayhuaman" in only:
            results["sacsayhuaman"] = sacsayhuaman_times(tmp)
            results["sacsayhuaman_machine"] = facts
            print_sacsayhuaman(results["sacsayhuaman"])
        if "limit" in only:
            results["limit"] = {"rows": limit_section(), "machine": facts}
        if "fragility_ida" in only:
            results["fragility_ida"] = dict(fragility_section(**(fragility or {})), machine=facts)
        if "compile" in only:
            results["compile"] = dict(compile_section(tmp), machine=facts)
        if "profile" in only:
            big = [n for n in sizes if n >= 500]  # the smallest of the big walls: its contacts, not its size, matter
            results["profile"] = dict(profile_section(tmp, [min(big) if big else 500], walls, steps), machine=facts)
    if baseline is not None:
        results["baseline"] = dict(bench_baseline.section(baseline, sizes, walls, rounds), machine=facts)
    results["machine"] = dict(facts, sections=sections, wall_s=time.time() - t0)
    out = write_results(results)
    print(f"written {out} ({time.time() - t0:.0f} s)")
    return results
