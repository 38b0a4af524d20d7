"""Run a case: validate everything, write the run specification, launch YADE, summarise.

``run(case_path, overrides, out_dir=None, threads=1)`` is what ``python -m drystone run``
and ``make run CASE=...`` call. All checks (case keys, geometry, time step, stage
parameters) happen here, before YADE starts; YADE only simulates.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from drystone import case as casemod
from drystone import paths, provenance, timestep
from drystone.geometry import blockfile as bf
from drystone.geometry import generators
from drystone.geometry import polyhedron as ph

TOWARDS = {"+x": [1.0, 0.0, 0.0], "-x": [-1.0, 0.0, 0.0], "+y": [0.0, 1.0, 0.0], "-y": [0.0, -1.0, 0.0]}
AXES = {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}


class RunError(RuntimeError):
    """A run that could not be prepared or did not complete."""


def _geometry(case: dict, where: str, out: Path, check_overlaps: bool = True) -> tuple[bf.BlockSet, dict]:
    geo = case["case"]["geometry"]
    if isinstance(geo, str):
        data = json.loads(Path(geo).read_text()) if Path(geo).is_file() else None
        bs = bf.load(geo, check_overlaps)
        source = {"file": geo, "sha256": hashlib.sha256(Path(geo).read_bytes()).hexdigest()}
    else:
        try:
            data = generators.generate(geo)
        except bf.GeometryError as exc:
            raise casemod.CaseError(f"{where}: [case] geometry: {exc}") from None
        bs = bf.parse(data, f"{where}: generated geometry {geo['generator']!r}", check_overlaps)
        source = {"generator": geo}
    bf.write(data, out / "geometry.json")
    return bs, source


def _materials(case: dict, bs: bf.BlockSet, where: str) -> dict:
    mats = {}
    for name, m in bs.materials.items():
        d = {"density": m.density, "kn": m.kn, "kt": m.kt, "mu": m.mu, "damping": m.damping}
        for k in ("kn", "kt", "mu", "damping"):
            if case["contact"][k] is not None:
                d[k] = case["contact"][k]
        mats[name] = d
    for name, over in case["materials"].items():
        if name not in mats:
            raise casemod.CaseError(f"{where}: [materials.{name}]: the geometry has no material {name!r} "
                                    f"(it has {sorted(mats)})")
        mats[name].update(over)
        lo, hi = bf.DENSITY_RANGE
        if not lo <= mats[name]["density"] <= hi:
            raise casemod.CaseError(f"{where}: [materials.{name}] 'density' must be in [{lo:g}, {hi:g}] kg/m^3, "
                                    f"got {mats[name]['density']:g}")
    return mats


def _excitation(s: dict, where: str, out: Path, k: int) -> tuple[np.ndarray, float, dict]:
    """Acceleration samples (m/s^2), their step (s) and metadata for an excitation stage
    (sine, white noise or record: drystone/motions/excitation.py), saved beside the run."""
    from drystone.motions import excitation as mex

    try:
        acc, dt, meta = mex.for_stage(s)
    except (ValueError, FileNotFoundError, KeyError, OSError) as exc:
        raise casemod.CaseError(f"{where}: [[stages]] #{k + 1} ({s['motion']}): {exc}") from None
    acc = np.asarray(acc, float)
    if not np.all(np.isfinite(acc)):
        raise casemod.CaseError(f"{where}: [[stages]] #{k + 1}: the excitation has non-finite samples")
    name = f"excitation_{k + 1}.npy"
    np.save(out / name, acc)
    meta = dict(meta, acc_file=name, dt_s=dt, pga_m_s2=float(np.abs(acc).max()),
                pga_g=float(np.abs(acc).max() / 9.80665), direction=s["direction"])
    return acc, dt, meta


def _check_force_depth(f: dict, k: int, bs: bf.BlockSet, mats: dict, where: str) -> None:
    """Refuse an applied force the penalty contact cannot hold: pressed on its largest face,
    the block would sink F / (K_n A) into its support, more than the depth at which the run
    stops as tunnelling (drystone/stability.py)."""
    from drystone import stability

    b = bs.block(f["block"])
    area = timestep.largest_face_area(b.vertices)
    force = math.hypot(*f["force"])
    depth = force / (mats[b.material]["kn"] * area)
    # its support is not known here: the thinnest block of the geometry bounds it
    limit = stability.TUNNEL_FRACTION * min(float(ph.extent(c.vertices).min()) for c in bs.blocks)
    if depth > limit:
        raise casemod.CaseError(
            f"{where}: [[forces]] #{k + 1}: {force:.3g} N on block {f['block']} would press it {depth:.3g} m into "
            f"its support (K_n {mats[b.material]['kn']:.3g} N/m^3 x its largest face {area:.3g} m^2), more than "
            f"{limit:.3g} m ({stability.TUNNEL_FRACTION:g} x the thinnest block): the blocks would pass through "
            "each other")


def initial_relative_velocity(s: dict, meta: dict) -> list[float]:
    """Velocity (m/s, platform frame) every free block gets when an excitation stage begins.

    ``start = "displacement"`` (sine only) imposes the paper's Eq. 9 as the base displacement
    d(t) = (A / w^2) sin(w t) from t = 0 (stage time), the base at rest before. Its velocity
    d'(t) = (A / w) cos(w t) jumps from 0 to v_b = A / w at t = 0, while its acceleration
    d''(t) = -A sin(w t) is what ``motions.generators.sine`` samples (and the load programme
    applies as the body force -d'' e). The jump is an acceleration impulse v_b delta(t) e that
    the samples cannot carry: at t = 0+ the free blocks, held only by finite contact forces,
    still have their world velocity (zero), so relative to the platform they move at
    0 - v_b e = -(A / w) e. With A = 0.5 m/s^2: 0.080 m/s at 1 Hz, 0.8 m/s at 0.1 Hz.
    ``start = "rest"`` (and every other motion) gives zero. At the end of the stage nothing
    is applied: the base keeps its final velocity (an inertial frame, no load on the wall)."""
    if s.get("start", "rest") != "displacement":
        return [0.0, 0.0, 0.0]
    info = meta["info"]
    v_b = info["amplitude_m_s2"] / (2.0 * math.pi * info["frequency_hz"])
    return [0.0 - v_b * c for c in AXES[s["direction"]]]


def resolve(case: dict, where: str, out: Path, check_overlaps: bool = True) -> dict:
    """Turn a validated case into the run specification YADE executes (files it needs,
    the geometry and excitation samples, are written into ``out``)."""
    bs, geo_source = _geometry(case, where, out, check_overlaps)
    mats = _materials(case, bs, where)
    ids = set(bs.ids())
    free = set(bs.ids("free"))
    for c in case["output"]["contacts"]:
        for b in c["blocks"]:
            if b not in ids:
                raise casemod.CaseError(f"{where}: [output] contact {c['name']!r}: no block {b} in the geometry")
    for k, f in enumerate(case["forces"]):
        if f["block"] not in free:
            raise casemod.CaseError(f"{where}: [[forces]] block {f['block']} is not a free block")
        _check_force_depth(f, k, bs, mats, where)
    detection = case["contact"]["detection"]
    if detection == "native" and case["contact"]["law"] != "penalty_coulomb":
        raise casemod.CaseError(f"{where}: [contact] 'detection' = 'native' needs law = 'penalty_coulomb' "
                                f"(the stock law runs on YADE's own contact geometry)")
    if detection == "auto":
        detection = "native" if case["contact"]["law"] == "penalty_coulomb" else "yade"
    tb = case["analysis"]["tilt_block"]
    if tb is not None and tb not in free:
        raise casemod.CaseError(f"{where}: [analysis] 'tilt_block' {tb} is not a free block")

    blocks = [{"id": b.id, "role": b.role, "material": b.material, "vertices": b.vertices.tolist(),
               "blocked_dofs": b.blocked_dofs} for b in bs.blocks]
    # time step
    damp = max([m["damping"] for m in mats.values()] + [j.get("damping", 0.0) for j in bs.joints])
    mats_dt = {n: dict(m, damping=damp) for n, m in mats.items()}
    dt_crit, crit = timestep.critical_step(blocks, mats_dt)
    step = case["time"]["step"]
    if step == "auto":
        dt = case["time"]["safety"] * dt_crit
    else:
        if step > dt_crit:
            raise casemod.CaseError(
                f"{where}: [time] 'step' = {step:g} s exceeds the critical step {dt_crit:.3g} s "
                f"(block {crit['block']}: mass {crit['mass_kg']:.3g} kg, contact stiffness "
                f"{crit['stiffness_N_per_m']:.3g} N/m, damping {crit['damping']}); use a smaller step or 'auto'")
        dt = step

    # stages
    stages, t, tilt, excitations = [], 0.0, 0.0, []
    for k, s in enumerate(case["stages"]):
        kind = s["type"]
        params: dict = {}
        if kind == "gravity":
            params = {"ramp": s["ramp"]}
            dur = s["duration"]
        elif kind == "settlement":
            if s["block"] not in ids or s["block"] in free:
                raise casemod.CaseError(f"{where}: [[stages]] #{k + 1}: settlement block {s['block']} must be a "
                                        "fixed block of the geometry")
            params = {"block": s["block"], "displacement": s["displacement"]}
            dur = s["duration"]
        elif kind == "tilt":
            target = s["to_deg"] if s["to_deg"] is not None else s["max_deg"]
            if target <= tilt:
                raise casemod.CaseError(f"{where}: [[stages]] #{k + 1}: tilt target {target} deg is not above "
                                        f"the current {tilt} deg")
            dur = (target - tilt) / s["rate_deg_s"]
            tilt = target
            params = {"rate_deg_s": s["rate_deg_s"], "towards": TOWARDS[s["towards"]],
                      "until_collapse": s["until_collapse"], "reaction_drop": s["reaction_drop"],
                      "after_collapse": s["after_collapse"]}
        elif kind == "excitation":
            if s["motion"] == "sine" and s["frequency_hz"] is not None and s["frequency_hz"] >= 0.5 / dt:
                raise casemod.CaseError(f"{where}: [[stages]] #{k + 1}: 'frequency_hz' = {s['frequency_hz']:g} Hz is at "
                                        f"or above the Nyquist frequency {0.5 / dt:g} Hz of the time step {dt:.3g} s")
            acc, sdt, meta = _excitation(s, where, out, k)
            dur = s["duration"] if s["duration"] is not None else (len(acc) - 1) * sdt
            params = {"acc_file": meta["acc_file"], "dt": sdt, "direction": AXES[s["direction"]],
                      "start": s["start"], "initial_relative_velocity": initial_relative_velocity(s, meta)}
            meta = dict(meta, start=s["start"], initial_relative_velocity_m_s=params["initial_relative_velocity"])
            excitations.append(dict(meta, stage=k + 1))
        else:  # rest
            dur = s["duration"]
            params = {"until_kinetic_below": s["until_kinetic_below"],
                      "until_kinetic_below_per_weight": s["until_kinetic_below_per_weight"],
                      "settle_window": s["settle_window"]}
            if params["until_kinetic_below"] is None and params["until_kinetic_below_per_weight"] is None:
                params = {}  # a plain rest: same fingerprint as before these keys existed
        stages.append({"kind": kind, "start": t, "end": t + dur, "params": params})
        t += dur

    timestep.step_count_check(dt, t, where, crit)  # absurd step counts (slivers, kn = 1e300) refused

    threshold = {}
    cd = case["output"]["collapse_displacement"]
    for b in bs.blocks:
        if b.role == "free":
            threshold[str(b.id)] = float(cd) if cd != "auto" else 0.5 * float(ph.extent(b.vertices).min())
    joint_overrides = {}
    for j in bs.joints:
        a, b = sorted(j["blocks"])
        joint_overrides[f"{a}-{b}"] = {k: v for k, v in j.items() if k != "blocks"}
    free_areas = [timestep.largest_face_area(b["vertices"]) for b in blocks if b["role"] == "free"]
    return {
        "name": case["case"]["name"], "out_dir": str(out), "law": case["contact"]["law"],
        "detection": detection,
        "dt": dt, "dt_critical": dt_crit, "dt_critical_detail": crit, "gravity": case["physics"]["gravity"],
        "materials": mats, "blocks": blocks, "joint_overrides": joint_overrides,
        "control_points": bs.control_points, "stages": stages, "forces": case["forces"],
        "output": {"interval": case["output"]["interval"], "contacts": case["output"]["contacts"]},
        "collapse_threshold": threshold, "onset_rate": case["output"]["onset_rate"],
        "onset_window_deg": case["output"]["onset_window"], "stock_shear_area": float(np.mean(free_areas)),
        "geometry_source": geo_source, "excitations": excitations, "analysis": case["analysis"],
    }


PHYSICS_KEYS = ("law", "detection", "dt", "gravity", "materials", "blocks", "joint_overrides", "forces",
                "collapse_threshold")  # the onset keys only date a collapse afterwards (postprocess)


def fingerprint(spec: dict) -> str:
    """SHA-256 of what a run simulates: geometry, materials, law, time step and the stages
    (an excitation by the content of its samples, not by its file's path). Two specs with
    the same fingerprint give the same run whatever their names and folders."""
    stages = []
    for st in spec["stages"]:
        params = dict(st["params"])
        if "acc_file" in params:
            acc = Path(spec["out_dir"]) / params["acc_file"]  # saved beside the run
            params["acc_file"] = hashlib.sha256(acc.read_bytes()).hexdigest()
        stages.append({"kind": st["kind"], "start": st["start"], "end": st["end"], "params": params})
    data = {k: spec.get(k) for k in PHYSICS_KEYS}
    data["stages"] = stages
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()


def _yade_command(spec_path: Path, threads: int) -> list[str]:
    yade = shutil.which("yade") or "/usr/bin/yade"
    script = paths.PACKAGE / "yade_scripts" / "run_case.py"
    return [sys.executable, yade, "-n", "-x", "-j", str(threads), str(script), str(spec_path)]


NOISE = ("Welcome to Yade", "TCP python prompt", "XMLRPC info provider", "Running script", "Using python version")


class FolderLock:
    """Exclusive lock on a results folder for the length of a run (``fcntl.flock`` on a
    hidden file beside it, released by the kernel if the process dies). A second run into
    the same folder is refused with RunError naming the holder's pid."""

    def __init__(self, out: Path):
        self.path = out.parent / f".{out.name}.lock"
        self.fd = None

    def __enter__(self):
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 64).decode(errors="replace").strip() or "?"
            os.close(fd)
            raise RunError(f"{self.path.parent / self.path.name[1:-5]}: another run (pid {holder}) is writing "
                           f"this results folder; wait for it or use another --out") from None
        os.ftruncate(fd, 0)
        os.write(fd, str(os.getpid()).encode())
        self.fd = fd
        return self

    def __exit__(self, *exc):
        os.close(self.fd)  # releases the lock; the (empty) lock file stays, harmlessly


def staging_folder(out: Path) -> Path:
    """Where a run is built before it replaces ``out`` (same filesystem: an atomic rename)."""
    return out.parent / f".{out.name}.partial"


def _swap_in(stage: Path, out: Path) -> None:
    """Replace ``out`` by the complete run in ``stage``; the old run is removed only after
    the new one is in place."""
    old = out.parent / f".{out.name}.old"
    shutil.rmtree(old, ignore_errors=True)
    if out.exists():
        os.replace(out, old)
    os.replace(stage, out)
    shutil.rmtree(old, ignore_errors=True)


def _simulate(spec_path: Path, threads: int, quiet: bool) -> int:
    """Run YADE on ``spec_path`` (its log to log.txt beside it); returns YADE's exit code.
    YADE runs in its own session, so a Ctrl-C reaches only this process, which then
    kills YADE (no orphan) and re-raises."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")  # YADE runs this interpreter: drystone is installed
    with open(spec_path.parent / "log.txt", "w") as log:
        proc = subprocess.Popen(_yade_command(spec_path, threads), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, env=env, cwd=paths.ROOT,
                                start_new_session=True)
        try:
            for line in proc.stdout:
                log.write(line)
                log.flush()  # sweeps read the progress of running jobs from log.txt
                if not quiet and not line.startswith(NOISE) and "verletDist is set to 0" not in line:
                    print(line, end="", flush=True)
            return proc.wait()
        except BaseException:  # Ctrl-C, SIGTERM (sweep workers), errors: never leave YADE running
            proc.kill()
            proc.wait()
            raise


def run(case_path, overrides=None, out_dir=None, threads=1, quiet=False, check_overlaps=True) -> dict:
    """Validate, simulate and summarise one case; returns the summary dict.

    Nothing in the results folder changes until the new run is complete: the case, its
    geometry, records and time step are checked and the run is built in a staging folder
    beside it (``staging_folder``), then swapped in; a failed or interrupted run leaves the
    previous results as they were (and its log in the staging folder). summary.json is
    the last file written. The folder is locked for the run (``FolderLock``).
    ``check_overlaps=False`` skips the geometry's pairwise overlap test (sweeps have run
    it once for all their runs)."""
    from drystone.postprocess import plots
    from drystone.postprocess import summary as summ  # plain Python

    case_path = Path(case_path)
    case = casemod.load(case_path, overrides or [])
    where = str(case_path)
    out = Path(out_dir) if out_dir else paths.RESULTS / case["case"]["name"]
    with FolderLock(out):
        stage = staging_folder(out)
        shutil.rmtree(stage, ignore_errors=True)
        stage.mkdir(parents=True)
        t0 = time.time()
        spec = resolve(case, where, stage, check_overlaps=check_overlaps)
        spec["out_dir"] = str(out)  # where the run will live (YADE writes beside its spec.json)
        spec["provenance"] = provenance.collect(case_path, case, overrides or [])
        spec_path = stage / "spec.json"
        spec_path.write_text(json.dumps(spec, indent=1))
        if not quiet:
            print(f"[{spec['name']}] dt = {spec['dt']:.3g} s (critical {spec['dt_critical']:.3g} s), "
                  f"{len(spec['blocks'])} blocks, {spec['stages'][-1]['end']:.2f} s simulated, law {spec['law']}, "
                  f"{spec['stages'][-1]['end'] / spec['dt']:.0f} steps", flush=True)
        rc = _simulate(spec_path, threads, quiet)
        if (stage / "failure.txt").is_file():  # stopped by a stability check (drystone/stability.py)
            raise RunError(f"{where}: the simulation was stopped: {(stage / 'failure.txt').read_text().strip()}; "
                           f"{out} is unchanged; log {stage / 'log.txt'}")
        if rc != 0 or not (stage / "histories.npz").is_file():
            tail = (stage / "log.txt").read_text(errors="replace").splitlines()[-20:]
            raise RunError(f"{where}: YADE failed (exit {rc}); {out} is unchanged; log {stage / 'log.txt'}:\n"
                           + "\n".join(tail))
        summary = summ.build(spec, stage)
        summary["wall_time_total_s"] = time.time() - t0
        figures = plots.standard(stage, summary)
        try:
            summ.write(summary, stage)  # last: the marker of a complete run
        except ValueError as exc:
            raise RunError(f"{where}: {exc}; {out} is unchanged") from None
        _swap_in(stage, out)
    if not quiet:
        print(f"[{spec['name']}] results in {out}: summary.json, histories.npz, "
              + ", ".join(f.name for f in figures), flush=True)
    return summary


def resummarise(out) -> dict:
    """Rebuild a finished run's summary.json from its spec, histories and run info with
    the current post-processing (e.g. the collapse onset rule); the figures are kept."""
    from drystone.postprocess import summary as summ

    out = Path(out)
    old = json.loads((out / "summary.json").read_text())
    summary = summ.build(json.loads((out / "spec.json").read_text()), out)
    if "wall_time_total_s" in old:
        summary["wall_time_total_s"] = old["wall_time_total_s"]
    summ.write(summary, out)
    return summary


def run_dict(case_dict: dict, case_path: Path, overrides=None, **kw) -> dict:
    """Write a case dict as a TOML file and run it (used by tests, sweeps and bench)."""
    case_path = Path(case_path)
    case_path.write_text(to_toml(case_dict))
    return run(case_path, overrides, **kw)


def to_toml(d: dict) -> str:
    """Minimal TOML writer for case dicts (tables, arrays of tables, scalars, lists)."""
    lines = []

    def scalar(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, float) and math.isinf(v):
            return "inf"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{k} = {scalar(x)}" for k, x in v.items()) + "}"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(scalar(x) for x in v) + "]"
        return repr(v)

    for sec, body in d.items():
        if isinstance(body, list):
            for item in body:
                lines.append(f"[[{sec}]]")
                lines += [f"{k} = {scalar(v)}" for k, v in item.items()]
                lines.append("")
        elif sec == "materials":
            for name, m in body.items():
                lines.append(f"[materials.{name}]")
                lines += [f"{k} = {scalar(v)}" for k, v in m.items()]
                lines.append("")
        else:
            lines.append(f"[{sec}]")
            lines += [f"{k} = {scalar(v)}" for k, v in body.items()]
            lines.append("")
    return "\n".join(lines)
