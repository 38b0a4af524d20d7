"""Collapse of a stone (``stone``: the package's one geometric rule, applied to every run by
drystone/analyses/common.py ``outcome``) and collapse angle of a tilt run from its recorded
motion (plain Python, no YADE).

A tilt run stops shortly after a collapse is *detected* (drystone/yade_scripts/run_case.py: the
vertical reaction drops or a block moves more than its threshold). Detection lags the
instability by the time the blocks need to move far, and at a faster tilt rate more tilt
goes by in that time. The collapse angle is therefore the tilt where the motion that led
to the detection began: the middle of the first window of ``window_deg`` of tilt over
which some block moved faster than ``rate_m_per_deg`` per degree of tilt (and never fell
back below half of it before the detection).

Motion is measured per degree of tilt, not per second: a wall leaning quasi-statically
moves a fixed distance per degree whatever the rate, so the same threshold marks the same
state at 0.2 and at 1 deg/s (a speed threshold of 5 mm/s is 5 mm/deg at 1 deg/s but
25 mm/deg at 0.2 deg/s, which dates the onset later in slow tilts).
"""
from __future__ import annotations

import math

import numpy as np

def tipping(axis_z, L: float, D: float, H: float) -> tuple[float, float]:
    """(lean, tipping angle), rad, of a stone of bounding box L x D x H (x along the wall,
    y out of plane, z up) whose own vertical axis is now the unit vector ``axis_z``: the
    lean is the axis's angle from the vertical; the tipping angle in the direction phi it
    leans towards is atan(w / (H/2)), w = |cos phi| L/2 + |sin phi| D/2 the half-width of
    the box in that direction (its centroid is then over the edge it rocks on)."""
    zx, zy, zz = (float(v) for v in axis_z)
    lean = math.acos(max(-1.0, min(1.0, zz)))
    phi = math.atan2(zy, zx)
    w = abs(math.cos(phi)) * 0.5 * L + abs(math.sin(phi)) * 0.5 * D
    return lean, math.atan2(w, 0.5 * H)


def stone(extent, u, rotvec) -> tuple[list[str], bool]:
    """The collapse rule for one stone still in the model (docs/physics.md, "Collapse of a
    stone"). ``extent`` (L, D, H): its bounding box at rest (m; x along the wall, y out of
    plane, z up), ``u`` its centroid's displacement (m) and ``rotvec`` its rotation (rotation
    vector, rad) since it stood (the end of gravity), in the platform frame. It has collapsed
    when it fell (u_z < -H/2: its centroid dropped by more than half its height), overturned
    (it leans past its tipping angle, ``tipping``) or was pushed out of the wall (|u_y| >
    D/2: its centroid is no longer over the bed it was built on). Returns (the reasons among
    "fell", "overturned", "out_of_plane"; [] when it stands) and whether a standing stone
    slid along the wall by more than half its length (|u_x| > L/2: in-plane sliding, a damage
    reported as such, not collapse). A stone that left the model has collapsed (the caller
    knows it: it has no displacement left to judge)."""
    from scipy.spatial.transform import Rotation

    L, D, H = (float(x) for x in extent)
    reasons = []
    if u[2] < -0.5 * H:
        reasons.append("fell")
    lean, tip = tipping(Rotation.from_rotvec(np.asarray(rotvec, float)).apply([0.0, 0.0, 1.0]), L, D, H)
    if lean > tip:
        reasons.append("overturned")
    if abs(u[1]) > 0.5 * D:
        reasons.append("out_of_plane")
    return reasons, (not reasons and abs(u[0]) > 0.5 * L)


#: the rule in one line (reports, summary.json, the run's console)
RULE = ("a stone has collapsed when, at the end of the run, it left the model, or its centroid dropped by more "
        "than half its height, or it leans past its tipping angle (overturned), or its centroid moved out of "
        "plane by more than half its depth; residual displacements short of that are damage, and a stone "
        "sliding along the wall by more than half its length is reported as in-plane sliding, not collapse "
        "(drystone/mechanics/collapse.py stone, drystone/analyses/common.py outcome; docs/physics.md)")


def reference_sample(spec: dict, t) -> int:
    """The sample the rule measures from: the end of the last gravity stage (0 without one)."""
    from drystone.model.spec import stage_type

    t = np.asarray(t, float)
    grav = [st for st in spec["stages"] if stage_type(st) == "gravity"]
    return min(int(np.searchsorted(t, grav[-1]["end"] - 1e-9)), len(t) - 1) if grav and len(t) else 0


def run_stones(spec: dict, h: dict, left=()) -> dict[int, dict]:
    """``stone`` applied to every free stone of a finished run at its last sample: block id ->
    {"why": reasons (["left_model"] for a stone in ``left``, the ids that left the model),
    "in_plane_sliding": bool, "u_m": its centroid's displacement since ``reference_sample``
    (None when it left)}. ``spec`` a spec.json dict, ``h`` its histories (t, block_ids, pos,
    quat). The one reading of collapse of summary.json, the run's console and the analyses."""
    from drystone.mechanics import rotations

    t = np.asarray(h["t"], float)
    i0 = reference_sample(spec, t)
    pos, quat = np.asarray(h["pos"], float), np.asarray(h["quat"], float)
    u = pos[-1] - pos[i0]
    rot = rotations.relative_rotation_vectors(quat[-1], quat[i0])
    verts = {int(b["id"]): np.asarray(b["vertices"], float) for b in spec["blocks"]}
    left = {int(b) for b in left}
    out = {}
    for j, b in enumerate(int(x) for x in h["block_ids"]):
        if b in left:
            out[b] = {"why": ["left_model"], "in_plane_sliding": False, "u_m": None}
            continue
        reasons, slid = stone(np.ptp(verts[b], axis=0), u[j], rot[j])
        out[b] = {"why": reasons, "in_plane_sliding": bool(slid), "u_m": u[j]}
    return out


RATE_M_PER_DEG = 5e-3  # m of block displacement per degree of tilt
WINDOW_DEG = 0.2  # deg of tilt over which the displacement is measured (filters rattling)


def onset(tilt_deg, pos, t, detected_time_s, rate_m_per_deg=RATE_M_PER_DEG, window_deg=WINDOW_DEG) -> dict | None:
    """Onset of the motion that led to a collapse detected at ``detected_time_s`` (s).

    ``tilt_deg`` (n,) platform tilt of each sample (deg), ``pos`` (n, blocks, 3) block
    positions in the platform frame (m), ``t`` (n,) sample times (s). Returns
    ``{"angle_deg", "time_s", "index"}`` (index: the block that moved fastest, in the
    order of ``pos``), or None when no window before the detection exceeded the rate.
    """
    tilt_deg, t = np.asarray(tilt_deg, float), np.asarray(t, float)
    pos = np.asarray(pos, float)
    if rate_m_per_deg <= 0 or window_deg <= 0:
        raise ValueError(f"onset: rate ({rate_m_per_deg}) and window ({window_deg}) must be positive")
    found = None
    last = int(np.searchsorted(t, detected_time_s, side="right"))
    peak = np.maximum.accumulate(tilt_deg[:last]) if last else tilt_deg[:0]
    for i in range(1, last):
        if tilt_deg[i] < peak[i]:  # not tilting further (a tilt held or going back): no rate per degree
            continue
        j = int(np.searchsorted(peak[:i + 1], tilt_deg[i] - window_deg, side="left"))
        dtilt = tilt_deg[i] - tilt_deg[j]
        if dtilt < 0.5 * window_deg:  # the tilt has only just started
            continue
        moved = np.linalg.norm(pos[i] - pos[j], axis=1) / dtilt
        k = int(np.argmax(moved))
        if moved[k] > rate_m_per_deg:
            if found is None:
                found = {"angle_deg": float(0.5 * (tilt_deg[i] + tilt_deg[j])), "time_s": float(0.5 * (t[i] + t[j])),
                         "index": k}
        elif moved[k] < 0.5 * rate_m_per_deg:
            found = None
    return found


REACTION_DROP = 0.05  # fraction of the moving blocks' weight (the tilt stage's default reaction_drop)


def reaction_drop(t, tilt_deg, reaction_N, weight_N, active=None, drop=REACTION_DROP) -> dict:
    """The paper's collapse angle (Sacsayhuaman paper §3.2, Figure 13: "the vertical
    reaction drops sharply at 33.5 s, corresponding to a rotation of 14.3 deg").

    Definition: the platform tilt at the first recorded sample, among the ``active`` ones
    (the samples of the tilt stages), at which the vertical reaction of the moving blocks
    on the platform and the fixed blocks, ``reaction_N`` (N, along the true vertical, up),
    is below ``(1 - drop) * weight_N``, with ``weight_N`` the weight of the moving blocks
    (N) and ``drop`` a fraction (default 5 %, the tilt stage's ``reaction_drop``).

    Measured along the true vertical, the reaction of a wall at rest equals its weight at
    any tilt (the platform carries all of it; along the platform's normal it would fall as
    cos(tilt), 3 % at 14 deg, without any collapse); it drops only while blocks accelerate
    downwards, i.e. fall. This is the rule the run itself uses to stop
    (drystone/yade_scripts/run_case.py, evaluated at the same recorded samples), so when the run's
    criterion was ``reaction_drop`` the angle equals its detection angle.

    ``t`` (n,) s, ``tilt_deg`` (n,) deg, ``reaction_N`` (n,) N, ``active`` (n,) bool or
    None (all samples). Returns ``{"angle_deg", "time_s", "reaction_N", "fraction",
    "min_fraction", "drop", "weight_N"}``: ``fraction`` = reaction / weight at that sample,
    ``min_fraction`` the lowest over the active samples; ``angle_deg`` and ``time_s`` are
    None when the reaction never dropped that far in the recorded history.
    """
    t, tilt_deg = np.asarray(t, float), np.asarray(tilt_deg, float)
    r = np.asarray(reaction_N, float)
    if not weight_N > 0 or not 0 < drop < 1:
        raise ValueError(f"reaction_drop: weight ({weight_N} N) must be positive and drop ({drop}) in (0, 1)")
    act = np.ones(len(t), bool) if active is None else np.asarray(active, bool)
    frac = r / weight_N
    out = {"angle_deg": None, "time_s": None, "reaction_N": None, "fraction": None,
           "min_fraction": float(frac[act].min()) if act.any() else None, "drop": float(drop),
           "weight_N": float(weight_N)}
    hit = np.flatnonzero(act & (frac < 1.0 - drop))
    if len(hit):
        i = int(hit[0])
        out.update(angle_deg=float(tilt_deg[i]), time_s=float(t[i]), reaction_N=float(r[i]), fraction=float(frac[i]))
    return out
