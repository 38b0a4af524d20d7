"""Tilt-table validation report (Sacsayhuaman paper §3.2), plain Python, on the ``tilt``
analysis (drystone/analyses/tilt.py).

Every run is one ``tilt`` analysis of cases/tilt_wall.toml towards +y (``run``: the
generated Santa-Cruz wall, its gravity stage, then the platform tilted with a lead-in to
10 deg and on until collapse, at most 25 deg, 3 s run after the detection), in four groups
(``GROUPS``), each a folder of analyses ``results/tilt/<group>/<run>/`` (tilt.json,
report.html, the run in runs/towards_+y/):

* ``seeds``: generated walls (seeds 0-4), FEM calibration, the faster protocol ``FAST``;
* ``extruded``: the same walls with a constant section (every stone extruded through the
  mean thickness), to show what the stones' varying depth does;
* ``rate``: the paper's protocol (``PAPER``: 1 deg/s to 10 deg, then 0.2 deg/s) on seed 0,
  to check the faster protocol of the seeds (the collapse angle may change by at most
  0.2 deg);
* ``sensitivity``: mu, K_n and the DEM calibration of Table 1 on seed 0.

``build`` writes ``results/tilt/summary.json`` (``collapse_angles_deg``: one per seed, with
the parameters), ``results/tilt/report.md`` and figures: the wall at the paper's Figure 12
angles and the vertical reaction against time and tilt for every seed (Figure 13).
Missing runs are reported as missing, never filled in. Angles in degrees.

Two collapse angles per wall, both as the ``tilt`` analysis reports them (tilt.json, from the
run's summary.json): the *onset* angle, its headline (where the motion that led to the
collapse began, drystone/mechanics/collapse.py ``onset``: ``collapse_angle_deg``) and the
paper's *reaction-drop* angle (its Figure 13: the tilt at which the vertical reaction of the
moving stones first falls 5 % below their weight, drystone/mechanics/collapse.py
``reaction_drop``: ``reaction_drop_angle_deg``), the paper's own reading of collapse, named
as such. The headline (``headline``) is the constant-section walls (every stone extruded
through the mean thickness, as the paper's model was built: the like-for-like comparison),
beside the varying-depth walls (our hypothesis for the real, irregular walls).
"""
from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths
from drystone.postprocess import compare, markdown
from drystone.model.spec import stage_type

OUT = paths.RESULTS / "tilt"
CASE = paths.CASES / "tilt_wall.toml"
RATE_TOLERANCE_DEG = 0.2  # a faster rate may not move the collapse angle more than this (the paper's protocol's step)
#: tilt protocols: the lead-in (to_deg, rate deg/s), then the rate (deg/s) until collapse
FAST = {"lead": (10.0, 2.0), "rate": 1.0}   # the seeds' faster quasi-static protocol
PAPER = {"lead": (10.0, 1.0), "rate": 0.2}  # the paper's (and cases/tilt_wall.toml's own)
#: every run: at most this tilt (deg), run this long after the detection (s: long enough for the reaction drop)
MAX_DEG, AFTER_COLLAPSE_S = 25.0, 3.0
SEEDS = (0, 1, 2, 3, 4)
#: group -> (protocol, [(run name, overrides of cases/tilt_wall.toml)]); the FEM calibration of
#: Table 1 is the case's own (its run is seeds/seed_0); the sensitivity runs are one change at a
#: time around it (K_t = K_n / 2 as the paper's §3.2) and Table 1's DEM calibration column
GROUPS = {
    "seeds": (FAST, [(f"seed_{k}", [f"case.geometry.seed={k}"]) for k in SEEDS]),
    "extruded": (FAST, [(f"seed_{k}", [f"case.geometry.seed={k}", "case.geometry.depth_spread=0.0"]) for k in SEEDS]),
    "rate": (PAPER, [("paper_seed_0", ["case.geometry.seed=0"])]),
    "sensitivity": (FAST, [(name, ["case.geometry.seed=0"] + over) for name, over in (
        ("mu_0.3", ["contact.mu=0.3"]), ("mu_0.5", ["contact.mu=0.5"]), ("mu_0.6", ["contact.mu=0.6"]),
        ("mu_0.7", ["contact.mu=0.7"]), ("kn_5e7", ["contact.kn=5e7", "contact.kt=2.5e7"]),
        ("kn_5e8", ["contact.kn=5e8", "contact.kt=2.5e8"]),
        ("dem_calibration", ["contact.kn=5e7", "contact.kt=2.5e7", "contact.mu=0.7",
                             "materials.stone.density=2400.0"]))]),
}
#: the run folder of one tilt analysis (drystone/analyses/tilt.py: towards +y)
RUN = Path("runs") / "towards_+y"


def tilt_run(group: str, name: str, overrides: list, root: Path, backend="local", address=None) -> dict:
    """One run of a group: the tilt analysis of cases/tilt_wall.toml towards +y with the
    group's protocol, into ``root``/<name>/; tilt.json's +y direction."""
    from drystone.analyses import tilt as analysis

    proto = GROUPS[group][0]
    res = analysis.tilt(CASE, ("+y",), out=Path(root) / name, workers=1, backend=backend, address=address,
                        rate=proto["rate"], max_deg=MAX_DEG, overrides=overrides, lead=proto["lead"],
                        after_collapse=AFTER_COLLAPSE_S)
    return res["directions"]["+y"]


def run_group(group: str, out: Path = OUT, workers=None, backend="local", address=None, log=print) -> dict:
    """Run (or reuse) the tilt analyses of one group (``GROUPS``) into ``out``/<group>/<run>/,
    up to ``workers`` at once (each one run); returns {run name: tilt.json's +y direction}."""
    from drystone.studies import in_parallel

    proto, todo = GROUPS[group]
    root = Path(out) / group
    root.mkdir(parents=True, exist_ok=True)
    atomic.write_text(root / "runs.json", json.dumps({"group": group, "protocol": proto,
                                                      "runs": [n for n, _ in todo]}, indent=1) + "\n")
    n = max(1, min(workers or os.cpu_count() or 1, len(todo)))
    log(f"[tilt study] {group}: {len(todo)} tilt analyses, {n} at a time")
    res = in_parallel(tilt_run, [(group, name, over, root, backend, address) for name, over in todo], n)
    return {name: r for (name, _), r in zip(todo, res)}


def runs(root: Path) -> list[dict]:
    """One row per run of a group folder (``run_group``; runs without summary.json are
    listed as not finished), in the group's order (its runs.json, else by name)."""
    root = Path(root)
    listed = json.loads((root / "runs.json").read_text())["runs"] if (root / "runs.json").is_file() else []
    names = listed or sorted(p.name for p in root.iterdir() if p.is_dir())
    rows = []
    for name in names:
        folder = root / name / RUN
        p = folder / "summary.json"
        if not p.is_file():
            rows.append({"name": name, "finished": False})
            continue
        s = json.loads(p.read_text())
        col = s.get("collapse") or {}
        mat = next(iter(s["inputs"]["materials"].values()))
        tilts = [st for st in s["inputs"]["stages"] if stage_type(st) == "tilt"]
        rows.append({
            "name": name, "finished": True, "folder": str(folder),
            "collapse_angle_deg": s.get("collapse_angle_deg"),
            "reaction_drop_angle_deg": _reaction_drop_angle(folder, s),
            "detected_angle_deg": col.get("detected_angle_deg"),
            "criterion": col.get("criterion"), "first_blocks": col.get("first_blocks"),
            "onset_block": col.get("onset_block"),
            "seed": s["inputs"]["geometry"].get("generator", {}).get("seed"),
            "depth_spread": _generated(folder).get("depth_spread", 0.0),
            "thickness_m": _generated(folder).get("thickness"),
            "materials": mat, "rates_deg_s": [st["params"]["rate_deg_s"] for st in tilts],
            "overrides": s["inputs"]["provenance"]["overrides"],
            "wall_time_s": s["run"]["wall_time_s"], "steps": s["run"]["steps"], "dt_s": s["run"]["dt_s"],
            "simulated_time_s": s["run"]["simulated_time_s"],
        })
    return rows


def _reaction_drop_angle(folder: Path, s: dict) -> float | None:
    """The run's reaction-drop angle (deg): from summary.json, or, for a summary written
    before it was reported, from the run's histories (drystone/postprocess/summary.py)."""
    if "reaction_drop_angle_deg" in s:
        return s["reaction_drop_angle_deg"]
    if not s.get("collapse"):
        return None
    try:
        from drystone.postprocess import summary as summ

        spec = json.loads((folder / "spec.json").read_text())
        return summ.tilt_reaction_drop(spec, summ.load_histories(folder))["angle_deg"]
    except (OSError, KeyError, ValueError):
        return None


def _generated(folder: Path) -> dict:
    """The generator's parameters of a run's wall (geometry.json), {} if not generated."""
    g = folder / "geometry.json"
    return json.loads(g.read_text()).get("generator", {}) if g.is_file() else {}


def paired(rows: list[dict], other: list[dict], key: str = "collapse_angle_deg") -> dict | None:
    """Per seed, the angle ``key`` of ``rows`` minus that of ``other`` (same seeds), with
    the statistics of ``other``: what the geometry change between the two sweeps does.
    The reaction-drop angles are paired the same way under ``reaction_drop``."""
    def by_seed(rr, k):
        return {r["seed"]: r.get(k) for r in rr if r["finished"] and r.get(k) is not None}

    a, b = by_seed(rows, key), by_seed(other, key)
    common = sorted(set(a) & set(b))
    if not common:
        return None
    d = np.array([a[k] - b[k] for k in common])
    out = {"seeds": common, "angles_deg": [b[k] for k in common], "differences_deg": d.tolist(),
           "mean_difference_deg": float(d.mean()), "statistics": seed_statistics(other, key),
           "depth_spread": next((r["depth_spread"] for r in other if r["finished"]), None)}
    if key == "collapse_angle_deg":
        out["reaction_drop"] = paired(rows, other, "reaction_drop_angle_deg")
    return out


def seed_statistics(rows: list[dict], key: str = "collapse_angle_deg") -> dict:
    """Mean, sample standard deviation and range of the angles ``key`` (the onset
    ``collapse_angle_deg`` or ``reaction_drop_angle_deg``) of finished runs; runs without
    one (no collapse, or no reaction drop before the run stopped) are counted, not averaged."""
    done = [r for r in rows if r["finished"]]
    angles = [r.get(key) for r in done if r.get(key) is not None]
    p = compare.paper("sacsayhuaman")["tilt"]
    lo = p["experiment_collapse_deg"] - p["experiment_collapse_sd_deg"]
    hi = p["experiment_collapse_deg"] + p["experiment_collapse_sd_deg"]
    out = {"n_runs": len(rows), "n_finished": len(done), "n_collapsed": len(angles),
           "experiment_deg": p["experiment_collapse_deg"], "experiment_sd_deg": p["experiment_collapse_sd_deg"],
           "experiment_range_deg": [lo, hi], "paper_model_deg": p["model_collapse_deg"]}
    if angles:
        a = np.asarray(angles, float)
        out.update(mean_deg=float(a.mean()), sd_deg=float(a.std(ddof=1)) if len(a) > 1 else None,
                   min_deg=float(a.min()), max_deg=float(a.max()),
                   mean_within_experiment_sd=bool(lo <= a.mean() <= hi),
                   n_within_experiment_sd=int(np.sum((a >= lo) & (a <= hi))))
    return out


def rate_check(seed_rows: list[dict], rate_rows: list[dict]) -> dict | None:
    """The paper-protocol run against the faster-protocol run of the same seed."""
    paper_run = next((r for r in rate_rows if r["finished"]), None)
    if paper_run is None:
        return None
    fast = next((r for r in seed_rows if r["finished"] and r["seed"] == paper_run["seed"]), None)
    if fast is None or fast["collapse_angle_deg"] is None or paper_run["collapse_angle_deg"] is None:
        return {"seed": paper_run["seed"], "complete": False}
    diff = fast["collapse_angle_deg"] - paper_run["collapse_angle_deg"]
    return {"seed": paper_run["seed"], "complete": True,
            "paper_protocol": {"rates_deg_s": paper_run["rates_deg_s"], "angle_deg": paper_run["collapse_angle_deg"],
                               "wall_time_s": paper_run["wall_time_s"]},
            "fast_protocol": {"rates_deg_s": fast["rates_deg_s"], "angle_deg": fast["collapse_angle_deg"],
                              "wall_time_s": fast["wall_time_s"]},
            "difference_deg": diff, "tolerance_deg": RATE_TOLERANCE_DEG,
            "within_tolerance": bool(abs(diff) <= RATE_TOLERANCE_DEG)}


def _fmt(v, spec=".2f"):
    return "-" if v is None else format(v, spec)


HEADLINE = (("constant_section", "constant section (every stone extruded through the mean thickness, as the "
                                 "paper's model): like for like"),
            ("varying_depth", "stones of varying depth (our hypothesis for the real walls)"))


def headline(constant: list[dict], varying: list[dict]) -> dict:
    """Both collapse angles (onset, reaction drop) of both geometries; the constant-section
    walls first: they are built as the paper's model was (extruded), so they are the
    like-for-like comparison with its 14.3 deg."""
    out = {"like_for_like": "constant_section", "rows": []}
    for (key, label), rows in zip(HEADLINE, (constant, varying)):
        done = [r for r in rows if r["finished"]]
        out["rows"].append({
            "walls": key, "label": label, "n_runs": len(rows),
            "seeds": [r["seed"] for r in done],
            "onset_angles_deg": [r["collapse_angle_deg"] for r in done],
            "reaction_drop_angles_deg": [r.get("reaction_drop_angle_deg") for r in done],
            "onset": seed_statistics(rows) if rows else None,
            "reaction_drop": seed_statistics(rows, "reaction_drop_angle_deg") if rows else None})
    return out


def _angles_cell(values: list, st: dict | None) -> str:
    if not values:
        return "not run"
    txt = ", ".join(_fmt(v) for v in values)
    if st and "mean_deg" in st:
        txt += f": mean {st['mean_deg']:.2f}" + (f", sd {st['sd_deg']:.2f}" if st.get("sd_deg") is not None else "")
    return txt


def _within_cell(st: dict | None) -> str:
    if not st or "mean_deg" not in st:
        return "-"
    return f"{st['n_within_experiment_sd']} of {st['n_collapsed']}"


def headline_md(summary: dict) -> list[str]:
    """The headline table: experiment, the paper's model, and our two geometries with both
    collapse angles."""
    p = summary["paper"]
    hl = summary.get("headline") or {"rows": []}
    lines = ["## Collapse angle: both definitions, both geometries", "",
             "Onset: the tilt where the motion that led to the collapse began (5 mm of block motion per degree "
             "of tilt over 0.2 deg; drystone/mechanics/collapse.py `onset`). Reaction drop: the paper's criterion (Fig. 13), "
             "the tilt at which the vertical reaction of the moving stones on the platform and fixed course first "
             f"falls below {1 - summary.get('reaction_drop_fraction', 0.05):.2f} of their weight "
             "(drystone/mechanics/collapse.py `reaction_drop`). The constant-section walls are the like-for-like "
             "comparison with the paper's model (its blocks were extruded from the front face).", "",
             "| walls | onset angle (deg) | reaction-drop angle (deg) | within the experiment's ±1 sd (onset; drop) |",
             "|---|---|---|---|",
             f"| experiment (Santa-Cruz et al., 3 walls) | {p['experiment_collapse_deg']} ± "
             f"{p['experiment_collapse_sd_deg']} | | |",
             f"| paper's model (constant section, FEM calibration) | | {p['model_collapse_deg']} | |"]
    for r in hl["rows"]:
        bold = "**" if r["walls"] == hl.get("like_for_like") else ""
        lines.append(f"| {bold}{r['label']}{bold}, seeds {', '.join(str(k) for k in r['seeds']) or '-'} | "
                     f"{_angles_cell(r['onset_angles_deg'], r['onset'])} | "
                     f"{_angles_cell(r['reaction_drop_angles_deg'], r['reaction_drop'])} | "
                     f"{_within_cell(r['onset'])}; {_within_cell(r['reaction_drop'])} |")
    return lines + [""]


def report_md(summary: dict) -> str:
    st = summary["seeds"]
    lines = ["# Tilt-table validation (Sacsayhuaman paper §3.2)", "",
             f"Walls: {summary['wall']}", "",
             f"Experiment (Santa-Cruz et al.): {st['experiment_deg']} ± {st['experiment_sd_deg']} deg; "
             f"paper's model {st['paper_model_deg']} deg.", "",
             "## Assumed inputs", ""]
    assumed = summary.get("assumed") or {}
    seen = []
    for walls in ("constant_section", "varying_depth"):
        seen += [a for a in assumed.get(walls, []) if a not in seen]
    lines += [f"* {a}" for a in seen] or ["* (no run found: the generator's assumptions are listed by its runs)"]
    lines += [""]
    lines += headline_md(summary)
    lines += ["## Collapse angle per wall of varying depth (FEM calibration of Table 1)", "",
              "| run | seed | onset angle (deg) | reaction-drop angle (deg) | detected at (deg) | criterion | "
              "first blocks | wall time (s) |",
              "|---|---|---|---|---|---|---|---|"]
    for r in summary["seed_runs"]:
        if not r["finished"]:
            lines.append(f"| {r['name']} | | not run | | | | | |")
            continue
        lines.append(f"| {r['name']} | {r['seed']} | {_fmt(r['collapse_angle_deg'])} | "
                     f"{_fmt(r.get('reaction_drop_angle_deg'))} | {_fmt(r['detected_angle_deg'])} "
                     f"| {r['criterion'] or 'no collapse'} | {r['first_blocks']} | {r['wall_time_s']:.0f} |")
    if "mean_deg" in st:
        lines += ["", f"Mean {st['mean_deg']:.2f} deg, standard deviation {_fmt(st['sd_deg'])} deg, range "
                      f"{st['min_deg']:.2f}-{st['max_deg']:.2f} deg over {st['n_collapsed']} walls; "
                      f"the mean is {'within' if st['mean_within_experiment_sd'] else 'outside'} one standard "
                      f"deviation of the experiment ({st['experiment_range_deg'][0]:.2f}-"
                      f"{st['experiment_range_deg'][1]:.2f} deg); {st['n_within_experiment_sd']} of "
                      f"{st['n_collapsed']} walls are."]
    ex = summary.get("extruded")
    if ex:
        es = ex["statistics"]
        lines += ["", "## Constant section (stones extruded through the mean thickness)", "",
                  "The same walls (seeds, front faces, weight) with every stone extruded through "
                  f"{_fmt(summary['thickness_m'], '.4f')} m instead of having a depth of its own "
                  f"(depth spread {_fmt(ex['depth_spread'], 'g')} instead of {_fmt(summary['depth_spread'], '.3g')}).",
                  "",
                  "| seed | onset, extruded (deg) | onset, varying depth (deg) | difference (deg) | "
                  "reaction drop, extruded (deg) | reaction drop, varying depth (deg) | difference (deg) |",
                  "|---|---|---|---|---|---|---|"]
        rd = ex.get("reaction_drop") or {"seeds": [], "angles_deg": [], "differences_deg": []}
        rdm = {k: (a, d) for k, a, d in zip(rd["seeds"], rd["angles_deg"], rd["differences_deg"])}
        for k, a, d in zip(ex["seeds"], ex["angles_deg"], ex["differences_deg"]):
            ra, rdd = rdm.get(k, (None, None))
            lines.append(f"| {k} | {a:.2f} | {a + d:.2f} | {d:+.2f} | {_fmt(ra)} | "
                         f"{_fmt(None if ra is None else ra + rdd)} | {_fmt(rdd, '+.2f')} |")
        if "mean_deg" in es:
            lines += ["", f"Extruded: mean {es['mean_deg']:.2f} deg, standard deviation {_fmt(es['sd_deg'])} deg "
                          f"({'within' if es['mean_within_experiment_sd'] else 'outside'} the experiment's "
                          f"one-sd band; {es['n_within_experiment_sd']} of {es['n_collapsed']} walls within). "
                          f"Varying depth lowers the angle by {-ex['mean_difference_deg']:.2f} deg on average."]
    rc = summary.get("rate_check")
    lines += ["", "## Tilt rate", ""]
    if rc and rc.get("complete"):
        lines.append(f"Seed {rc['seed']}: paper protocol {rc['paper_protocol']['rates_deg_s']} deg/s "
                     f"-> {rc['paper_protocol']['angle_deg']:.2f} deg; faster protocol "
                     f"{rc['fast_protocol']['rates_deg_s']} deg/s -> {rc['fast_protocol']['angle_deg']:.2f} deg; "
                     f"difference {rc['difference_deg']:+.2f} deg (tolerance ±{rc['tolerance_deg']} deg: "
                     f"{'within' if rc['within_tolerance'] else 'OUTSIDE'}).")
    else:
        lines.append("Not available: run `make tilt-rate` (the paper's 0.2 deg/s protocol on seed 0).")
    sens = summary.get("sensitivity") or []
    lines += ["", "## Sensitivity (seed 0)", ""]
    if sens:
        lines += ["| run | density (kg/m³) | K_n (N/m³) | K_t (N/m³) | mu | collapse angle (deg) | first blocks |",
                  "|---|---|---|---|---|---|---|"]
        for r in sens:
            if not r["finished"]:
                lines.append(f"| {r['name']} | | | | | not run | |")
                continue
            m = r["materials"]
            lines.append(f"| {r['name']} | {m['density']:g} | {m['kn']:.3g} | {m['kt']:.3g} | {m['mu']:g} | "
                         f"{_fmt(r['collapse_angle_deg'])} | {r['first_blocks']} |")
    else:
        lines.append("Not available: run `make tilt-sensitivity`.")
    if summary.get("figures"):
        lines += ["", "## Figures", ""] + [f"![{Path(f).stem}]({Path(f).name})" for f in summary["figures"]]
    return "\n".join(lines) + "\n"


def reaction_figure(rows: list[dict], path: Path) -> Path | None:
    """Vertical reaction of the moving blocks against time and tilt, every finished run
    (the paper's Figure 13), collapse angles marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from drystone.model.loading import LoadProgramme
    from drystone.postprocess import summary as summ

    done = [r for r in rows if r["finished"]]
    if not done:
        return None
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    for r in done:
        out = Path(r["folder"])
        spec = json.loads((out / "spec.json").read_text())
        h = summ.load_histories(out)
        prog = LoadProgramme.from_spec(spec)
        up = np.array([prog.true_vertical(t) for t in h["t"]])
        rv = -np.einsum("ij,ij->i", h["reaction"], up)
        label = (f"{r['name']}: onset {_fmt(r['collapse_angle_deg'])} deg (:), "
                 f"reaction drop {_fmt(r.get('reaction_drop_angle_deg'))} deg (--)")
        line, = a1.plot(h["t"], rv, lw=0.9, label=label)
        a2.plot(h["tilt_deg"], rv, lw=0.9, color=line.get_color())
        if r["collapse_angle_deg"] is not None:
            a2.axvline(r["collapse_angle_deg"], color=line.get_color(), ls=":", lw=0.8)  # onset
        if r.get("reaction_drop_angle_deg") is not None:
            a2.axvline(r["reaction_drop_angle_deg"], color=line.get_color(), ls="--", lw=0.8)  # reaction drop
    p = compare.paper("sacsayhuaman")["tilt"]
    a2.axvspan(p["experiment_collapse_deg"] - p["experiment_collapse_sd_deg"],
               p["experiment_collapse_deg"] + p["experiment_collapse_sd_deg"], color="0.85", zorder=0,
               label="experiment ±1 sd")
    a1.set_xlabel("time (s)")
    a2.set_xlabel("platform tilt (deg)")
    for a in (a1, a2):
        a.set_ylabel("vertical reaction of the moving stones (N)")
        a.grid(alpha=0.3)
    a1.legend(fontsize=7)
    a2.legend(fontsize=7, loc="lower left")
    fig.suptitle("Tilt-table walls: vertical reaction on the platform and fixed course (cf. paper Fig. 13)",
                 fontsize=10)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)


def snapshot_figure(run: dict, path: Path) -> Path:
    """The wall (world frame) at the paper's Figure 12 angles, at our collapse angle and
    at the end of the run."""
    from drystone.postprocess import snapshots

    p = compare.paper("sacsayhuaman")["tilt"]
    angles = [a for a in p["figure12_angles_deg"][:4]]
    if run.get("collapse_angle_deg") is not None:
        angles.append(round(run["collapse_angle_deg"], 2))
    times = snapshots.times_at_angles(run["folder"], angles) + [1e9]
    titles = [f"{a:g} deg" for a in angles] + ["end of run"]
    if run.get("collapse_angle_deg") is not None:
        titles[len(angles) - 1] = f"{angles[-1]:g} deg (our collapse onset)"
    return snapshots.render(run["folder"], times, path, world=True, elev=12, azim=-35, titles=titles,
                            frame_on_first=True)


def build(seeds=None, rate=None, sensitivity=None, out: Path = OUT, figures: bool = True,
          extruded=None) -> dict:
    """The summary and report of the groups' folders (default ``out``/<group>/)."""
    out = Path(out)
    seeds = Path(seeds or out / "seeds")
    extruded = Path(extruded or out / "extruded")
    rate = Path(rate or out / "rate")
    sensitivity = Path(sensitivity or out / "sensitivity")
    if not seeds.is_dir():
        raise FileNotFoundError(f"{seeds}: no tilt runs (run `make tilt` first)")
    seed_rows = runs(seeds)
    ext_rows = runs(extruded) if extruded.is_dir() else []
    rate_rows = runs(rate) if rate.is_dir() else []
    sens_rows = runs(sensitivity) if sensitivity.is_dir() else []
    done = [r for r in seed_rows if r["finished"]]
    ref = next((r for r in done if r["seed"] == 0), None)
    if sens_rows and ref is not None:  # the FEM calibration itself is the seed-0 run of the seed sweep
        sens_rows = [dict(ref, name=f"fem_calibration ({seeds.name}/{ref['name']})")] + sens_rows
    out.mkdir(parents=True, exist_ok=True)
    p = compare.paper("sacsayhuaman")["tilt"]
    summary = {
        "units": "angles in deg, stiffness N/m^3, density kg/m^3, times s",
        "wall": (f"generated irregular dry-stone walls {p['wall_length_m']} x {p['wall_height_m']} m weighing "
                 f"{p['wall_weight_N']} N (drystone/geometry/irregular_wall.py: tilt_wall), first course fixed"),
        "collapse_angles_deg": [r["collapse_angle_deg"] for r in done],
        "seeds": seed_statistics(seed_rows),
        "seed_values": [r["seed"] for r in done],
        "parameters": {"materials": done[0]["materials"] if done else None,
                       "tilt_rates_deg_s": done[0]["rates_deg_s"] if done else None,
                       "overrides": done[0]["overrides"] if done else None},
        "seed_runs": seed_rows,
        "depth_spread": done[0]["depth_spread"] if done else None,
        "thickness_m": done[0]["thickness_m"] if done else None,
        "extruded": paired(seed_rows, ext_rows) if ext_rows else None,
        "headline": headline(ext_rows, seed_rows),
        "assumed": {"constant_section": _assumed(ext_rows), "varying_depth": _assumed(seed_rows)},
        "reaction_drop_fraction": _drop_fraction(done),
        "rate_check": rate_check(seed_rows, rate_rows),
        "sensitivity": sens_rows,
        "paper": p,
        "figures": [],
    }
    summary["seeds"]["collapse_angles_deg"] = summary["collapse_angles_deg"]
    if figures and done:
        f = reaction_figure(seed_rows + [r for r in rate_rows if r["finished"]], out / "reaction.png")
        summary["figures"].append(str(f))
        if any(r["finished"] for r in ext_rows):
            f = reaction_figure(ext_rows, out / "reaction_constant_section.png")
            summary["figures"].append(str(f))
        show = next((r for r in rate_rows if r["finished"]), done[0])
        summary["figures"].append(str(snapshot_figure(show, out / "snapshots.png")))
    atomic.write_text(out / "summary.json", json.dumps(summary, indent=1, default=_json_default))
    markdown.write(out / "report.md", report_md(summary))  # and report.html beside it
    return summary


def _assumed(rows: list[dict]) -> list[str]:
    """The generator's assumed inputs of the first finished run (geometry.json), seed-free."""
    import re

    for r in rows:
        if r["finished"]:
            return [re.sub(r" \(seed \d+\)", "", a) for a in _generated(Path(r["folder"])).get("assumed", [])]
    return []


def _drop_fraction(done: list[dict]) -> float:
    """The reaction_drop fraction of the runs' until_collapse stage (5 % by default)."""
    for r in done:
        try:
            spec = json.loads((Path(r["folder"]) / "spec.json").read_text())
        except (OSError, KeyError, ValueError):
            continue
        for st in spec["stages"]:
            if stage_type(st) == "tilt" and st["params"].get("until_collapse"):
                return float(st["params"].get("reaction_drop", 0.05))
    return 0.05


def _json_default(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return str(v)


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.studies.tilt", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--run", nargs="+", choices=tuple(GROUPS), default=[], metavar="GROUP",
                    help=f"run (or reuse) these groups' tilt analyses first: {', '.join(GROUPS)}")
    ap.add_argument("--workers", type=int, default=None, help="tilt analyses at once (default: cores)")
    ap.add_argument("--dask", metavar="ADDRESS", default=None, help="Dask scheduler address, or 'local'")
    ap.add_argument("--seeds", help="folder of the seeds group (results/tilt/seeds)")
    ap.add_argument("--rate", help="folder of the rate check (results/tilt/rate)")
    ap.add_argument("--sensitivity", help="folder of the sensitivity group (results/tilt/sensitivity)")
    ap.add_argument("--extruded", help="folder of the constant-section walls (results/tilt/extruded)")
    ap.add_argument("--out", default=str(OUT))
    a = ap.parse_args(argv)
    failed = []
    for g in a.run:
        res = run_group(g, Path(a.out), a.workers, "dask" if a.dask else "local", a.dask)
        failed += [f"{g}/{n}/{r.get('run')}" for n, r in res.items() if r.get("status") != "done"]
    build(a.seeds, a.rate, a.sensitivity, Path(a.out), extruded=a.extruded)
    print((Path(a.out) / "report.md").read_text())
    print(f"written {Path(a.out) / 'summary.json'}")
    if failed:  # the runs went on in other processes: said here, not through sweep.FAILED_RUNS
        import sys

        print(f"error: {len(failed)} run(s) failed, their results are missing from the report: "
              + ", ".join(failed[:5]) + (", ..." if len(failed) > 5 else "")
              + " (FAILED.txt and log.txt in each folder; run the study again to retry them)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
