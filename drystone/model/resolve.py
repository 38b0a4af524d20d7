"""The run specification: a validated case (drystone/model/case.py) turned into what YADE
executes (a drystone.model.spec.Spec, written as spec.json), in jobs: geometry (``_geometry``),
materials (``_materials``), checks of the blocks the case names (``_check_references``),
contact detection, the time step (``_time_step``), the stages (``_stages``: each type's
``resolve`` in drystone/model/stages.py), collapse thresholds and joints (``_collapse_threshold``,
``_joint_overrides``). ``fingerprint`` says what a spec simulates. Core layer: imports
geometry, motions and the core, never postprocess.
"""
from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from drystone.model import case as casemod
from drystone import inputfiles
from drystone.mechanics import laws, overlap
from drystone.model import timestep
from drystone.geometry import blockfile as bf
from drystone.geometry import generators
from drystone.geometry import polyhedron as ph
from drystone.model.spec import SPEC_FORMAT, SPEC_VERSION, Spec, StageSpec, spec_dict  # noqa: F401
from drystone.model.loads import REGISTRY as LOAD_TYPES
from drystone.kept import Kept
from drystone.model.loads import LoadContext
from drystone.model.stages import AXES, REGISTRY, TOWARDS, ResolveContext, initial_relative_velocity  # noqa: F401


#: this process's geometries of the pure generators (``generators.PURE``), generated and checked (``_generated``), and the
#: text of their geometry.json, by their parameters (drystone/kept.py): a sweep or an analysis checks
#: every run's case before it runs them, and its runs share one wall
_GENERATED = Kept(8)
_WRITTEN = Kept(8)


def _generated(geo: dict, where: str, check_overlaps: bool) -> tuple[dict, bf.BlockSet, tuple | None]:
    """The block file of a generated geometry, its BlockSet (copies of the kept ones where the
    same pure generator was asked the same before) and its key in ``_GENERATED`` (None: not kept)."""
    def generate():
        try:
            data = generators.generate(geo)
        except bf.GeometryError as exc:
            raise casemod.CaseError(f"{where}: [case] geometry: {exc}") from None
        return data, bf.parse(data, f"{where}: generated geometry {geo['generator']!r}", check_overlaps)

    if geo.get("generator") not in generators.PURE:
        return (*generate(), None)
    key = (json.dumps(geo, sort_keys=True, default=repr), bool(check_overlaps))
    return (*_GENERATED.get(key, generate), key)


def _write_geometry(data: dict, path: Path, key: tuple | None) -> None:
    """geometry.json: the block file checked and written (``bf.write``), or, for a kept generated
    geometry written before, the same text again."""
    from drystone import atomic

    text = _WRITTEN.get(key) if key is not None else None
    if text is not None:
        atomic.write_text(path, text)
        return
    bf.write(data, path)
    if key is not None:
        _WRITTEN.put(key, path.read_text())


def _geometry(case: dict, where: str, out: Path, check_overlaps: bool = True) -> tuple[bf.BlockSet, dict]:
    geo = case["case"]["geometry"]
    if isinstance(geo, str):
        data = inputfiles.load_json(geo, bf.GeometryError, "block file")
        bs = bf.parse(data, geo, check_overlaps)
        source = {"file": geo, "sha256": hashlib.sha256(Path(geo).read_bytes()).hexdigest()}
        key = None
    else:
        data, bs, key = _generated(geo, where, check_overlaps)
        source = {"generator": geo}
    for b in bs.blocks:  # what the contact kernel cannot hold fails here, not inside YADE
        for k, part in enumerate(b.parts):
            why = overlap.too_large(part)
            if why:
                what = f"block {b.id}" + (f" part {k}" if len(b.parts) > 1 else "")
                raise bf.GeometryError(f"{geo if isinstance(geo, str) else where}: {what}: {why}")
    hovering = bf.hovering_fixed(bs)
    if hovering:
        import sys
        print(f"warning: {geo if isinstance(geo, str) else where}: fixed block(s) {hovering} stand neither on the "
              f"platform nor on fixed blocks that do (more than {bf.STANDING_TOL:g} m away, or 0.1 % of the "
              "wall's size if less): held in mid-air",
              file=sys.stderr)
    _write_geometry(data, out / "geometry.json", key)
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


def _check_force_depth(f: dict, k: int, bs: bf.BlockSet, mats: dict, where: str) -> None:
    """Refuse an applied force the penalty contact cannot hold: pressed on its largest face,
    the block would sink F / (K_n A) into its support, more than the depth at which the run
    stops as tunnelling (drystone/mechanics/stability.py)."""
    from drystone.mechanics import stability

    b = bs.block(f["block"])
    area = timestep.largest_face_area(b.points)
    force = math.hypot(*f["force"])
    depth = force / (mats[b.material]["kn"] * area)
    # its support is not known here: the thinnest block of the geometry bounds it
    limit = stability.TUNNEL_FRACTION * min(float(ph.extent(c.points).min()) for c in bs.blocks)
    if depth > limit:
        raise casemod.CaseError(
            f"{where}: [[forces]] #{k + 1}: {force:.3g} N on block {f['block']} would press it {depth:.3g} m into "
            f"its support (K_n {mats[b.material]['kn']:.3g} N/m^3 x its largest face {area:.3g} m^2), more than "
            f"{limit:.3g} m ({stability.TUNNEL_FRACTION:g} x the thinnest block): the blocks would pass through "
            "each other")


def _check_references(case: dict, bs: bf.BlockSet, mats: dict, where: str) -> None:
    """The blocks named by recorded contacts and applied forces exist (forces: free, and a
    load the penalty contact can hold)."""
    ids, free = set(bs.ids()), set(bs.ids("free"))
    for c in case["output"]["contacts"]:
        for b in c["blocks"]:
            if b not in ids:
                raise casemod.CaseError(f"{where}: [output] contact {c['name']!r}: no block {b} in the geometry")
    for k, f in enumerate(case["forces"]):
        if f["block"] not in free:
            raise casemod.CaseError(f"{where}: [[forces]] block {f['block']} is not a free block")
        _check_force_depth(f, k, bs, mats, where)


def _detection(case: dict, bs: bf.BlockSet, where: str) -> str:
    """The contact geometry: native or yade ('auto' follows the law). Stones of several
    parts need the native geometry (YADE's takes one convex body per stone pair)."""
    detection, law = case["contact"]["detection"], laws.get(case["contact"]["law"])
    if detection == "auto":
        detection = law.default_detection
    multi = [b.id for b in bs.blocks if len(b.parts) > 1]
    if multi and detection != "native":
        raise casemod.CaseError(
            f"{where}: block {multi[0]} has {len(bs.block(multi[0]).parts)} parts: stones of several convex parts "
            f"run with the project's law on the native contact geometry, not law = {law.name!r} with detection = "
            f"{detection!r} (YADE's geometry takes one convex body per pair; its stock law would need clumps it "
            "cannot hold shear for)")
    if case["contact"]["detection"] == "auto":
        return detection
    if detection not in law.detections:
        runs_on = [f"law = {n!r}" for n, other in laws.REGISTRY.items() if detection in other.detections]
        raise casemod.CaseError(f"{where}: [contact] 'detection' = {detection!r} needs {' or '.join(runs_on)} "
                                f"(law {law.name!r} runs on {', '.join(law.detections)} contact geometry only)")
    return detection


def _check_analysis(case: dict, bs: bf.BlockSet, where: str) -> None:
    tb = case["analysis"]["tilt_block"]
    if tb is not None and tb not in set(bs.ids("free")):
        raise casemod.CaseError(f"{where}: [analysis] 'tilt_block' {tb} is not a free block")


def _blocks(bs: bf.BlockSet) -> list[dict]:
    """The blocks as spec.json lists them (m, platform frame): a convex block its
    ``vertices``; a stone of several convex parts its ``parts`` and, as ``vertices``,
    every part's corners (for its extent and height, never as a body)."""
    out = []
    for b in bs.blocks:
        d = {"id": b.id, "role": b.role, "material": b.material, "vertices": b.points.tolist()}
        if len(b.parts) > 1:
            d["parts"] = [p.tolist() for p in b.parts]
        d["blocked_dofs"] = b.blocked_dofs
        out.append(d)
    return out


def _time_step(case: dict, bs: bf.BlockSet, blocks: list[dict], mats: dict, where: str) -> tuple[float, float, dict]:
    """(dt, critical dt, the critical contact) in s: 'auto' = safety x critical; a given
    step above the critical one is refused. The critical step takes the largest damping of
    any material or joint."""
    damp = max([m["damping"] for m in mats.values()] + [j.get("damping", 0.0) for j in bs.joints])
    mats_dt = {n: dict(m, damping=damp) for n, m in mats.items()}
    dt_crit, crit = timestep.critical_step(blocks, mats_dt)
    step = case["time"]["step"]
    if step == "auto":
        return case["time"]["safety"] * dt_crit, dt_crit, crit
    if step > dt_crit:
        raise casemod.CaseError(
            f"{where}: [time] 'step' = {step:g} s exceeds the critical step {dt_crit:.3g} s "
            f"(block {crit['block']}: mass {crit['mass_kg']:.3g} kg, contact stiffness "
            f"{crit['stiffness_N_per_m']:.3g} N/m, damping {crit['damping']}); use a smaller step or 'auto'")
    return step, dt_crit, crit


def _stages(case: dict, bs: bf.BlockSet, dt: float, where: str, out: Path) -> tuple[list[StageSpec], list[dict]]:
    """The resolved stages, contiguous from t = 0 (each type's ``resolve``: drystone/model/stages.py),
    and the excitations' metadata (their samples are saved into ``out``)."""
    ctx = ResolveContext(where=where, out=out, dt=dt, ids=set(bs.ids()), free=set(bs.ids("free")))
    stages, t = [], 0.0
    for k, s in enumerate(case["stages"]):
        dur, params = REGISTRY[s["type"]].resolve(s, k, ctx)
        stages.append(StageSpec(s["type"], t, t + dur, params))
        t += dur
    return stages, ctx.excitations


def _loads(case: dict, bs: bf.BlockSet, stages: list[StageSpec], dt: float, where: str, out: Path) -> tuple | None:
    """The resolved [[loads]] ({type, [name,] params}: each type's ``resolve``,
    drystone/model/loads.py), or None for a case without loads."""
    if not case.get("loads"):
        return None
    ctx = LoadContext(where=where, out=out, blocks=bs, stages=stages, gravity=case["physics"]["gravity"], dt=dt)
    out_loads = []
    for k, load in enumerate(case["loads"]):
        d = {"type": load["type"], "params": LOAD_TYPES[load["type"]].resolve(load, k, ctx)}
        if load["name"] is not None:
            d["name"] = load["name"]
        out_loads.append(d)
    return tuple(out_loads)


def _collapse_threshold(case: dict, bs: bf.BlockSet) -> dict[str, float]:
    """Per free block (id as a string): the displacement (m) beyond which it has collapsed."""
    cd = case["output"]["collapse_displacement"]
    return {str(b.id): float(cd) if cd != "auto" else 0.5 * float(ph.extent(b.points).min())
            for b in bs.blocks if b.role == "free"}


def _joint_overrides(bs: bf.BlockSet) -> dict[str, dict]:
    """The geometry's joints by "a-b" (a < b): the contact properties they override."""
    out = {}
    for j in bs.joints:
        a, b = sorted(j["blocks"])
        out[f"{a}-{b}"] = {k: v for k, v in j.items() if k != "blocks"}
    return out


def resolve(case: dict, where: str, out: Path, check_overlaps: bool = True) -> Spec:
    """Turn a validated case into the run specification YADE executes (files it needs,
    the geometry and excitation samples, are written into ``out``)."""
    bs, geo_source = _geometry(case, where, out, check_overlaps)
    mats = _materials(case, bs, where)
    _check_references(case, bs, mats, where)
    detection = _detection(case, bs, where)
    _check_analysis(case, bs, where)
    blocks = _blocks(bs)
    dt, dt_crit, crit = _time_step(case, bs, blocks, mats, where)
    stages, excitations = _stages(case, bs, dt, where, out)
    timestep.step_count_check(dt, stages[-1].end, where, crit)  # absurd step counts (slivers, kn = 1e300) refused
    loads = _loads(case, bs, stages, dt, where, out)
    free_areas = [timestep.largest_face_area(b["vertices"]) for b in blocks if b["role"] == "free"]
    return Spec(
        name=case["case"]["name"], out_dir=str(out), law=case["contact"]["law"], detection=detection,
        dt=dt, dt_critical=dt_crit, dt_critical_detail=crit, gravity=case["physics"]["gravity"],
        materials=mats, blocks=blocks, joint_overrides=_joint_overrides(bs), control_points=bs.control_points,
        stages=stages, forces=case["forces"],
        output={"interval": case["output"]["interval"], "contacts": case["output"]["contacts"],
                **({"stop_when_fallen": True} if case["output"].get("stop_when_fallen") else {})},
        collapse_threshold=_collapse_threshold(case, bs), onset_rate=case["output"]["onset_rate"],
        onset_window_deg=case["output"]["onset_window"], stock_shear_area=float(np.mean(free_areas)),
        geometry_source=geo_source, excitations=excitations, analysis=case["analysis"], loads=loads)


PHYSICS_KEYS = ("law", "detection", "dt", "gravity", "materials", "blocks", "joint_overrides", "forces",
                "collapse_threshold")  # the onset keys only date a collapse afterwards (postprocess)


def fingerprint(spec) -> str:
    """SHA-256 of what a run simulates: geometry, materials, law, time step and the stages
    (an excitation by the content of its samples, not by its file's path) and the loads. Two specs with
    the same fingerprint give the same run whatever their names and folders. ``spec``: a
    Spec or a spec.json dict of any version (the same physics gives the same hash)."""
    d = spec_dict(spec)
    stages = []
    for st in d["stages"]:
        params = dict(st["params"])
        if "acc_file" in params:
            acc = Path(d["out_dir"]) / params["acc_file"]  # saved beside the run
            params["acc_file"] = hashlib.sha256(acc.read_bytes()).hexdigest()
        # hashed under version 1's name "kind": runs finished before version 2 keep their fingerprint
        stages.append({"kind": st["type"], "start": st["start"], "end": st["end"], "params": params})
    data = {k: d.get(k) for k in PHYSICS_KEYS}
    data["stages"] = stages
    if d.get("loads"):  # hashed only where there are loads: the runs before them keep their fingerprint
        data["loads"] = d["loads"]
    if (d.get("output") or {}).get("stop_when_fallen"):  # a run cut short is another run (only then hashed)
        data["stop_when_fallen"] = True
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()
