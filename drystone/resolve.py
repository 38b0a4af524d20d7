"""The run specification: a validated case (drystone/case.py) turned into what YADE
executes (spec.json), in jobs: geometry (``_geometry``), materials (``_materials``), applied
forces (``_check_force_depth``), time step, stages (excitations: ``_excitation``,
``initial_relative_velocity``), collapse thresholds. ``fingerprint`` says what a spec
simulates. Core layer: imports geometry, motions and the core, never postprocess.
"""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from drystone import case as casemod
from drystone import contact
from drystone import timestep
from drystone.geometry import blockfile as bf
from drystone.geometry import generators
from drystone.geometry import polyhedron as ph
from drystone.units import G_STANDARD

TOWARDS = {"+x": [1.0, 0.0, 0.0], "-x": [-1.0, 0.0, 0.0], "+y": [0.0, 1.0, 0.0], "-y": [0.0, -1.0, 0.0]}
AXES = {"x": [1.0, 0.0, 0.0], "y": [0.0, 1.0, 0.0], "z": [0.0, 0.0, 1.0]}


#: spec.json's format name and version (histories.npz and summary.json carry theirs)
SPEC_FORMAT, SPEC_VERSION = "drystone-spec", 1


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
        d = {k: getattr(m, k) for k in bf.MATERIAL_PROPERTIES}
        for k in bf.CONTACT_PROPERTIES:
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
                pga_g=float(np.abs(acc).max() / G_STANDARD), direction=s["direction"])
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
        detection = contact.default_detection(case["contact"]["law"])
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
        "format": SPEC_FORMAT, "version": SPEC_VERSION,
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
