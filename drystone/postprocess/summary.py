"""Turn a run's histories into ``summary.json`` (plain Python, no YADE).

Conventions: positions are in the platform frame, so displacements are relative to the
platform; SI units; rotations as rotation vectors (axis x angle, rad) of each block
relative to its initial orientation. A block has *collapsed* by the package's one rule
(drystone/mechanics/collapse.py ``run_stones``: it left the model, fell, overturned or was
pushed out of the wall, measured from the end of gravity; ``collapse_why`` gives the reasons;
``in_plane_sliding`` a stone that slid along the wall by more than half its length, damage).
Residual displacements are damage measures, named as such: ``beyond_displacement_threshold``
says the residual exceeds ``displacement_threshold_m`` (case key
``output.collapse_displacement``, by default half the block's smallest dimension; a tilt
run's detection uses it to stop), not collapse. A block that left the model (drystone/mechanics/stability.py ``ModelRegion``: below
the supports' underside, or thrown farther than their size plus the fall height) has
collapsed and its motion is ``unbounded``: no residual, maximum or rotation is given for it
(from the sample it left on, its numbers describe nothing the model holds).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.mechanics import collapse, rotations, stability
from drystone.model.spec import spec_dict, stage_type


#: summary.json's format name and version
SUMMARY_FORMAT, SUMMARY_VERSION = "drystone-summary", 1


def load_histories(out: Path) -> dict:
    """histories.npz as a dict of arrays; named contacts under ``contacts[name][key]``."""
    with np.load(Path(out) / "histories.npz") as z:
        h = {k: z[k] for k in z.files if k not in ("format", "version")}
    contacts: dict[str, dict] = {}
    for k in list(h):
        if k.startswith("contact:"):
            _, name, field = k.split(":", 2)
            contacts.setdefault(name, {})[field] = h.pop(k)
    h["contacts"] = contacts
    return h


def left_model(spec: dict, h: dict) -> dict[int, dict]:
    """The free blocks that left the model (drystone/mechanics/stability.py ``ModelRegion``, from the
    blocks at t = 0): block id -> {"sample": first sample outside, "time_s", "where"}. The
    YADE driver applies the same rule to the same samples (run_info.json ``left_model``)."""
    if "blocks" not in spec or not len(h["t"]):
        return {}
    region = stability.ModelRegion.from_blocks(spec["blocks"])
    out = {}
    for j, k in enumerate(region.first_exits(h["t"], h["pos"])):
        if k is not None:
            out[int(h["block_ids"][j])] = {"sample": k, "time_s": float(h["t"][k]),
                                           "where": region.where(h["pos"][k, j])}
    return out


def block_table(spec: dict, h: dict, left: dict | None = None) -> dict:
    """Per block id: residual and maximum displacement, rotation (damage measures), collapsed
    by the one rule (module docstring); ``motion``
    "bounded", or "unbounded" for a block that left the model (``left``, default
    ``left_model``): collapsed, its residuals and maxima None, when and where it left."""
    left = left_model(spec, h) if left is None else left
    ids = [int(i) for i in h["block_ids"]]
    disp = h["pos"] - h["pos0"][None]
    rot = rotations.relative_rotation_vectors(h["quat"], h["quat0"][None])
    rule = collapse.run_stones(spec, h, left)
    out = {}
    for j, bid in enumerate(ids):
        thr = spec["collapse_threshold"][str(bid)]
        if bid in left:
            gone = left[bid]
            out[str(bid)] = {
                "motion": "unbounded",
                "left_model": {"time_s": gone["time_s"], "where": gone["where"]},
                "residual_displacement_m": None, "residual_displacement_norm_m": None,
                "max_displacement_norm_m": None, "residual_rotation_rad": None, "residual_rotation_angle_rad": None,
                "displacement_threshold_m": thr, "beyond_displacement_threshold": None,
                "fell": gone["where"].startswith("below"),
                "collapsed": True, "collapse_why": ["left_model"], "in_plane_sliding": False,
            }
            continue
        d = disp[:, j]
        nrm = np.linalg.norm(d, axis=1)
        why = rule[bid]["why"]
        out[str(bid)] = {
            "motion": "bounded",
            "residual_displacement_m": d[-1].tolist(),
            "residual_displacement_norm_m": float(nrm[-1]),
            "max_displacement_norm_m": float(nrm.max()),
            "residual_rotation_rad": rot[-1, j].tolist(),
            "residual_rotation_angle_rad": float(np.linalg.norm(rot[-1, j])),
            "displacement_threshold_m": thr,
            "beyond_displacement_threshold": bool(nrm[-1] > thr),
            "fell": "fell" in why,
            "collapsed": bool(why), "collapse_why": why, "in_plane_sliding": rule[bid]["in_plane_sliding"],
        }
    return out


def stage_residuals(spec: dict, h: dict, left: dict | None = None) -> list[dict]:
    """Displacement (m) of every free block at the end of each stage, relative to the
    platform: the residuals after each run of a repeated excitation; None for a block that
    had left the model by then (``left_model``)."""
    left = left_model(spec, h) if left is None else left
    disp = h["pos"] - h["pos0"][None]
    ids = [int(i) for i in h["block_ids"]]
    out = []
    for k, st in enumerate(spec["stages"]):
        i = int(np.searchsorted(h["t"], st["end"] + 1e-9) - 1)
        i = max(0, min(i, len(h["t"]) - 1))
        # summary.json (version 1) names a stage's type "kind"
        out.append({"stage": k + 1, "kind": stage_type(st), "end_s": st["end"], "sample_time_s": float(h["t"][i]),
                    "displacement_m": {str(b): None if b in left and left[b]["sample"] <= i else disp[i, j].tolist()
                                       for j, b in enumerate(ids)}})
    return out


def control_point_table(h: dict, spec: dict | None = None, left: dict | None = None) -> dict:
    """Per control point: max |relative displacement| per axis and in norm, and residual;
    None for a point on a block that left the model (``left``; ``spec`` gives each point's
    block)."""
    out = {}
    if h["cp"].size == 0:
        return out
    on = {c["name"]: c["block"] for c in (spec or {}).get("control_points", [])}
    rel = h["cp"] - h["cp0"][None]
    for j, name in enumerate(h["cp_names"]):
        if on.get(str(name)) in (left or {}):
            out[str(name)] = {"max_abs_relative_displacement_m": None, "max_relative_displacement_norm_m": None,
                              "residual_relative_displacement_m": None, "motion": "unbounded"}
            continue
        r = rel[:, j]
        nrm = np.linalg.norm(r, axis=1)
        out[str(name)] = {"max_abs_relative_displacement_m": np.abs(r).max(axis=0).tolist(),
                          "max_relative_displacement_norm_m": float(nrm.max()),
                          "residual_relative_displacement_m": r[-1].tolist()}
    return out


def penetration(spec: dict, h: dict, name: str) -> dict:
    """Final normal penetration of a named contact (m), from the blocks' relative
    displacement along the contact normal (kinematic, as the paper measures it) and from
    the contact's overlap volume / area."""
    c = h["contacts"][name]
    a, b = next(x["blocks"] for x in spec["output"]["contacts"] if x["name"] == name)
    ids = [int(i) for i in h["block_ids"]]
    n = c["normal"][-1]
    if not np.all(np.isfinite(n)):
        return {f"penetration_{a}_{b}_m": None}

    c_pt = c["point"][-1]

    def origin(bid):
        """Initial position of the material point of block bid that is now at c_pt."""
        if bid not in ids:
            return c_pt  # a non-moving block
        j = ids.index(bid)
        r = rotations.to_matrix(h["quat"][-1, j])
        r0 = rotations.to_matrix(h["quat0"][j])
        return h["pos0"][j] + r0 @ r.T @ (c_pt - h["pos"][-1, j])

    kin = float((origin(b) - origin(a)) @ n)
    area = float(c["area"][-1])
    out = {f"penetration_{a}_{b}_m": kin}
    if area > 0:
        out[f"penetration_{a}_{b}_contact_m"] = float(c["volume"][-1] / area)
        out[f"contact_area_{a}_{b}_m2"] = area
    out[f"normal_force_{a}_{b}_N"] = float(c["fn"][-1])
    return out


def block_tilt_deg(h: dict, bid: int) -> np.ndarray:
    """Rotation angle (deg) of a block over time."""
    j = [int(i) for i in h["block_ids"]].index(bid)
    rot = rotations.relative_rotation_vectors(h["quat"][:, j], h["quat0"][j][None])
    return np.degrees(np.linalg.norm(rot, axis=1))


#: relative sliding (m) of the two blocks of a contact that counts as gross slip
GROSS_SLIP = 1e-3


def relative_sliding(h: dict, a: int, b: int) -> np.ndarray:
    """Displacement (m) of block b's centroid in block a's frame since the first sample:
    its norm is the sliding of b over a (rigid rotations of the pair excluded)."""
    ids = [int(i) for i in h["block_ids"]]
    jb = ids.index(b)
    if a in ids:
        ja = ids.index(a)
        rot = rotations.to_matrix(h["quat"][:, ja])
        rel = np.einsum("kji,kj->ki", rot, h["pos"][:, jb] - h["pos"][:, ja])
    else:  # a non-moving block
        rel = h["pos"][:, jb].copy()
    return rel - rel[0]


def slip(spec: dict, h: dict, name: str, tilt_block: int | None) -> dict:
    """First gross slip of a named contact: the onset of the slipping phase (the contact at
    its Coulomb limit) that ends with block b sliding more than GROSS_SLIP over block a.
    A transient touch of the limit that does not lead to sliding (a jolt) is not a slip.
    Reports time (s), tangential and normal force (N), their ratio and, if ``tilt_block`` is
    given, that block's tilt (deg) at that moment."""
    c = h["contacts"][name]
    a, b = next(x["blocks"] for x in spec["output"]["contacts"] if x["name"] == name)
    none = {"slip_time_s": None, "slip_force_N": None, "slip_normal_force_N": None,
            "slip_force_ratio": None, "slip_tilt_deg": None}
    if b not in [int(i) for i in h["block_ids"]]:
        a, b = b, a
    moved = np.flatnonzero(np.linalg.norm(relative_sliding(h, a, b), axis=1) > GROSS_SLIP)
    flags = np.asarray(c["slipping"], bool)
    if len(moved) == 0 or not flags[: moved[0] + 1].any():
        return none
    k = int(moved[0])
    last = int(np.flatnonzero(flags[: k + 1])[-1])  # the slipping phase that leads to it
    i = last
    while i > 0 and flags[i - 1]:
        i -= 1
    ft = float(np.linalg.norm(c["ft"][i]))
    fn = float(c["fn"][i])
    out = {"slip_time_s": float(h["t"][i]), "slip_force_N": ft, "slip_normal_force_N": fn,
           "slip_force_ratio": ft / fn if fn > 0 else None}
    out["slip_tilt_deg"] = float(block_tilt_deg(h, tilt_block)[i]) if tilt_block is not None else None
    return out


def build(spec, out: Path) -> dict:
    """The summary of a finished run in folder ``out``; ``spec``: a drystone.model.spec.Spec or a
    spec.json dict of any version."""
    spec = spec_dict(spec)
    out = Path(out)
    h = load_histories(out)
    info = json.loads((out / "run_info.json").read_text())
    case = json.loads(json.dumps(spec["provenance"]))
    left = left_model(spec, h)
    s = {
        "format": SUMMARY_FORMAT, "version": SUMMARY_VERSION,
        "name": spec["name"],
        "law": spec["law"],
        "units": "SI (m, kg, s, N, rad); angles in deg where the key says so",
        "frame": "platform frame: x along the wall, y out of plane, z up; displacements relative to the platform",
        "run": {k: info[k] for k in ("steps", "simulated_time_s", "wall_time_s", "us_per_step",
                                     "python_us_per_step", "dt_s",
                                     "threads", "max_contacts", "final_contacts", "stopped_early", "yade_version")},
        "blocks": block_table(spec, h, left),
        "control_points": control_point_table(h, spec, left),
        "stage_residuals": stage_residuals(spec, h, left),
        "collapse_angle_deg": None,
        "inputs": {"geometry": spec["geometry_source"], "materials": spec["materials"],
                   "joint_overrides": spec["joint_overrides"], "stages": spec["stages"],
                   "excitations": spec["excitations"], "forces": spec["forces"], "dt_s": spec["dt"],
                   "dt_critical_s": spec["dt_critical"], "gravity_m_s2": spec["gravity"],
                   "displacement_threshold_m": spec["collapse_threshold"], "provenance": case,
                   "assumed": assumed_inputs(spec, out)},
    }
    # a last rest stage run until the kinetic energy settled: threshold, reached or not (None:
    # no such stage); velocity jumps of sines started as Eq. 9's displacement
    s["run"].update(settle=info.get("settle"), velocity_jumps=info.get("velocity_jumps", []))
    if info.get("stopped_when_fallen") is not None:  # output.stop_when_fallen: cut short once a stone fell
        s["run"]["stopped_when_fallen"] = info["stopped_when_fallen"]
    s["run"]["left_model"] = left_model_report(spec, h, left, info)
    s["run"]["motion"] = "unbounded" if left else "bounded"
    s["run"]["contact_stability"] = contact_stability(spec, info, len(left))
    if any(st["type"] == "tilt" for st in spec["stages"]):
        s["collapse"] = tilt_collapse(spec, h, info.get("collapse"))
        s["collapse_angle_deg"] = s["collapse"]["angle_deg"] if s["collapse"] else None
        s["reaction_drop_angle_deg"] = s["collapse"]["reaction_drop_angle_deg"] if s["collapse"] else None
    an = spec.get("analysis", {})
    if an.get("penetration"):
        s.update(penetration(spec, h, an["penetration"]))
    if an.get("slip"):
        s.update(slip(spec, h, an["slip"], an.get("tilt_block")))
    rv = h["reaction"][-1]
    s["final_reaction_N"] = rv.tolist()
    s["energy"] = energy_balance(h)
    return s


#: what summary.json's ``energy`` section says about its terms
ENERGY_CONVENTION = (
    "J, cumulative from the run's start; kinetic, elastic and potential at each sample's half step. "
    "work_loads > 0: the loads (gravity, tilt and base excitation as the body force m g_eff, applied forces, "
    "velocity jumps, settling blocks through their contacts) put energy into the free blocks; dissipated_* >= 0: "
    "energy taken out by the contacts' damping and by Coulomb slip. Balance B = kinetic + elastic + "
    "dissipated_damping + dissipated_friction + removed_kinetic - work_loads is constant (removed_kinetic: the "
    "kinetic energy carried out by the blocks taken out of the scene when they left the model); "
    "balance_error_J = max |B(t) - B(t0)| over "
    "the samples (t0 the first), balance_error_rel = that / the largest magnitude any term reached "
    "(docs/energy.md)")


def balance_history(h: dict) -> np.ndarray:
    """B(t) - B(t0) (J) at every sample, B = kinetic + elastic + dissipated_damping +
    dissipated_friction - work_loads (``ENERGY_CONVENTION``: the potential is not a term, the
    work of gravity is in work_loads); zero for an exact integration."""
    b = (np.asarray(h["kinetic"], float) + np.asarray(h["elastic"], float) + np.asarray(h["dissipated_damping"], float)
         + np.asarray(h["dissipated_friction"], float) - np.asarray(h["work_loads"], float))
    if "removed_kinetic" in h:  # carried out by the blocks that left the model (histories of this version on)
        b = b + np.asarray(h["removed_kinetic"], float)
    return b - b[0]


def energy_balance(h: dict) -> dict:
    """summary.json's ``energy`` section from the histories (drystone/mechanics/energy.py):
    the final value of each term (J), the balance error B(t) - B(t0) at its largest
    (``balance_error_J``, and when) and relative to the largest magnitude of any term
    (``balance_error_rel``); B = kinetic + elastic + dissipated_damping +
    dissipated_friction - work_loads (``ENERGY_CONVENTION``). Histories without the terms
    (older runs) or with NaN (the stock YADE law keeps no shear history nor damping to
    account) give None with a ``note``."""
    from drystone.mechanics.energy import TERMS

    keys = ("kinetic", "elastic", "potential") + TERMS
    out = {"units": "J", "convention": ENERGY_CONVENTION,
           "final": {f"{k}_J": None for k in keys}, "balance_error_J": None, "balance_error_rel": None,
           "balance_error_time_s": None, "scale_J": None}
    t = np.asarray(h.get("t", []), float)
    if not len(t) or any(k not in h for k in keys):
        out["note"] = "histories.npz has no energy terms (a run of an older version)"
        return out
    if "removed_kinetic" in h:
        keys = keys + ("removed_kinetic",)
        out["final"]["removed_kinetic_J"] = None
    v = {k: np.asarray(h[k], float) for k in keys}
    for k in keys:
        out["final"][f"{k}_J"] = float(v[k][-1]) if np.isfinite(v[k][-1]) else None
    if not all(np.all(np.isfinite(v[k])) for k in ("kinetic", "elastic") + TERMS):
        out["note"] = ("not accounted: this run's engine (the stock YADE law) keeps no elastic shear history nor "
                       "damping of the project's law; its histories hold NaN")
        return out
    err = np.abs(balance_history(v))
    i = int(np.argmax(err))
    scale = max(float(np.abs(v[k]).max()) for k in ("kinetic", "elastic") + TERMS)
    out.update(balance_error_J=float(err[i]), balance_error_time_s=float(t[i]), scale_J=scale,
               balance_error_rel=float(err[i] / scale) if scale > 0 else 0.0)
    return out


def left_model_report(spec: dict, h: dict, left: dict, info: dict) -> dict:
    """summary.json's ``run.left_model``: how many of the free blocks left the model, which
    and when (``left_model``), the region and its rule (drystone/mechanics/stability.py), and when the
    run stopped because every free block had left (run_info's ``all_left_model_s``)."""
    region = stability.ModelRegion.from_blocks(spec["blocks"]) if "blocks" in spec else None
    out = {"count": len(left), "free_blocks": len(h["block_ids"]),
           "blocks": [{"block": b, "time_s": r["time_s"], "where": r["where"]}
                      for b, r in sorted(left.items(), key=lambda x: (x[1]["time_s"], x[0]))],
           "stopped_all_left_s": info.get("all_left_model_s"),
           "region": region.as_dict() if region is not None else None, "rule": stability.REGION_RULE}
    if "removed_kinetic" in h:  # runs of this version: the driver took them out of the scene
        out["taken_out"] = ("each was taken out of the scene at the sample it left (no contact search, integration "
                            "nor energy from then on); its later samples repeat the position where it left")
        out["removed_kinetic_J"] = float(np.asarray(h["removed_kinetic"], float)[-1]) if len(h["t"]) else 0.0
    return out


def contact_stability(spec: dict, info: dict, blocks_left_model: int = 0) -> dict | None:
    """The largest omega dt any contact mode reached in the run (run_info's
    ``max_contact_omega_dt``, omega the contact's highest modal frequency from the damping
    kernel, drystone/mechanics/contact.py) against the central-difference limit 2 (sqrt(1 + xi^2) - xi)
    for the largest damping xi of the run's materials: a check of the automatic step, which
    is estimated from block masses before the run (drystone/model/timestep.py). ``within`` says
    the contacts were integrated stably, not that the motion is bounded: with
    ``blocks_left_model`` > 0 a ``note`` says so (run.left_model). None for runs without it
    (older runs, the stock law)."""
    w = info.get("max_contact_omega_dt")
    if w is None or not spec.get("materials"):
        return None
    xi = max(float(m.get("damping", 0.0)) for m in spec["materials"].values())
    limit = 2.0 * (np.sqrt(1.0 + xi * xi) - xi)
    out = {"max_omega_dt": float(w), "limit": float(limit), "within": bool(w < limit),
           "blocks_left_model": int(blocks_left_model)}
    if blocks_left_model:
        out["note"] = (f"{blocks_left_model} free block(s) left the model: 'within' covers the contacts only; "
                       "their motion is unbounded and has no residual (run.left_model)")
    return out


def vertical_reaction(spec: dict, h: dict) -> np.ndarray:
    """Vertical reaction (N) of the moving blocks on the platform and the fixed blocks at
    every sample: the recorded reaction force projected on the true (world) vertical, up."""
    from drystone.model.loading import LoadProgramme

    prog = LoadProgramme.from_spec(spec)
    up = np.array([prog.true_vertical(t) for t in h["t"]]).reshape(-1, 3)
    return -np.einsum("ij,ij->i", np.asarray(h["reaction"], float).reshape(-1, 3), up)


def tilt_reaction_drop(spec: dict, h: dict) -> dict:
    """The paper's reaction-drop collapse angle of a tilt run (drystone.mechanics.collapse.reaction_drop)
    over the samples of its tilt stages, with the drop fraction of its until_collapse stage
    (5 % by default) and the weight of the moving blocks (histories' masses x gravity)."""
    t = np.asarray(h["t"], float)
    tilts = [st for st in spec["stages"] if stage_type(st) == "tilt"]
    active = np.zeros(len(t), bool)
    for st in tilts:
        active |= (t > st["start"]) & (t <= st["end"] + 1e-9)
    drop = next((st["params"].get("reaction_drop") for st in tilts if st["params"].get("until_collapse")), None)
    if "mass" not in h:  # histories written before the masses were recorded
        return {"angle_deg": None, "time_s": None, "reaction_N": None, "fraction": None, "min_fraction": None,
                "drop": drop, "weight_N": None, "rule": "not available: histories.npz has no block masses"}
    weight = float(np.sum(h["mass"])) * spec["gravity"]
    out = collapse.reaction_drop(t, h["tilt_deg"], vertical_reaction(spec, h), weight, active,
                                 drop if drop is not None else collapse.REACTION_DROP)
    out["rule"] = ("first recorded sample of a tilt stage where the vertical reaction of the moving blocks "
                   "(true vertical) is below (1 - drop) x their weight (drystone/mechanics/collapse.py reaction_drop)")
    return out


def assumed_inputs(spec: dict, out: Path) -> list[str]:
    """The run's inputs that no paper gives, each labelled as assumed: what the geometry
    generator declares (its ``assumed`` list in geometry.json, e.g. a layout, course
    counts, a block orientation) and every record that is an analogue standing in for a
    paper's record (drystone/motions/catalogue.py)."""
    items = []
    g = Path(out) / "geometry.json"
    if g.is_file():
        items += [str(a) for a in json.loads(g.read_text()).get("generator", {}).get("assumed", [])]
    for k, e in enumerate(spec.get("excitations") or []):
        cat = (e.get("info") or {}).get("catalogue") or {}
        if cat.get("source_kind") == "analogue":
            items.append(f"excitation {k + 1}: record {cat.get('name')!r} is an ASSUMED analogue of "
                         f"{cat.get('stands_for')}: FEMA P695 {cat.get('fema_set')} record "
                         f"{e['info'].get('name', cat.get('fema_record_id'))} at {e.get('station')}")
    return items


def tilt_collapse(spec: dict, h: dict, detected: dict | None) -> dict | None:
    """The run's collapse detection (YADE side) with two angles: ``angle_deg`` (=
    ``onset_angle_deg``), dated back to the onset of the motion that led to it
    (drystone/mechanics/collapse.py onset; rule from the spec's onset keys), and
    ``reaction_drop_angle_deg``, the paper's criterion (its Figure 13: the tilt at which the
    vertical reaction first drops by the stage's ``reaction_drop`` fraction of the moving
    blocks' weight; None if it never did before the run stopped)."""
    if not detected:
        return None
    rate = spec.get("onset_rate", collapse.RATE_M_PER_DEG)
    window = spec.get("onset_window_deg", collapse.WINDOW_DEG)
    on = collapse.onset(h["tilt_deg"], h["pos"], h["t"], detected["detected_time_s"], rate, window)
    col = {k: v for k, v in detected.items() if k not in ("angle_deg", "time_s", "onset_block")}
    if on is None:  # no gradual start: the detection itself
        on = {"angle_deg": detected["detected_angle_deg"], "time_s": detected["detected_time_s"], "index": None}
    col.update(angle_deg=on["angle_deg"], time_s=on["time_s"],
               onset_block=None if on["index"] is None else int(h["block_ids"][on["index"]]),
               onset_rule={"rate_m_per_deg": rate, "window_deg": window})
    col["onset_angle_deg"] = col["angle_deg"]
    rd = tilt_reaction_drop(spec, h)
    col["reaction_drop_angle_deg"] = rd["angle_deg"]
    col["reaction_drop"] = rd
    return col


def _non_finite_keys(d, prefix="") -> list[str]:
    """Dotted keys of the non-finite floats in a nested dict/list."""
    out = []
    items = d.items() if isinstance(d, dict) else enumerate(d) if isinstance(d, (list, tuple)) else []
    for k, v in items:
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, float) and not np.isfinite(v):
            out.append(key)
        elif isinstance(v, (dict, list, tuple)):
            out += _non_finite_keys(v, key)
    return out


def write(summary: dict, out: Path) -> Path:
    """Write summary.json atomically (it is the marker of a complete run). A non-finite
    number raises ValueError naming it (JSON has no NaN or Infinity)."""
    p = Path(out) / "summary.json"
    try:
        text = json.dumps(summary, indent=1, default=float, allow_nan=False)
    except ValueError:
        raise ValueError(f"{p}: the summary has non-finite numbers ({', '.join(_non_finite_keys(summary)[:10])}); "
                         "not written") from None
    return atomic.write_text(p, text)
