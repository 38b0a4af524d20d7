"""Critical time step of the explicit integration, from the block geometry (no YADE).

For a free block i of mass m_i whose largest face has area A_i, the stiffest contact
mode is a normal one: the block pressed on two opposite faces by neighbours of similar
mass, omega_i^2 = 4 K_n A_i / m_i (the Gershgorin bound of a chain of such contacts).
Rocking modes are softer (the rocking stiffness of a face is K_n A b^2/12 against an
inertia larger than m b^2/12). A stone of several convex parts: m from the union's volume
(the parts' volumes summed) and A the largest face of the hull of its corners (the same estimate as
a convex block's; for a convex block cut into parts it is the uncut block's: the same step). With contact damping xi (fraction of critical) the
central-difference limit is dt_crit = (2 / omega)(sqrt(1 + xi^2) - xi).
"""
from __future__ import annotations

import math

import numpy as np

from drystone.kept import Kept
from drystone.mechanics import contact as law
from drystone.model.keys import CaseError
from drystone.geometry import polyhedron as ph

# Most steps a run may take: ~2 days of YADE at ~3 ms per step (a wall of a few dozen
# polyhedra). More means a degenerate input (a sliver block, an absurd kn or density).
MAX_STEPS = 5e7


#: the largest face areas and volumes this process has measured, by the hull's vertices (shape and
#: bytes): the runs of one wall, each checked before it runs and again when it runs, measure each
#: stone once
_MEASURED = Kept(100_000)


def _measured(what: str, vertices, measure) -> float:
    v = np.ascontiguousarray(vertices, dtype=float)
    key = (what, v.shape, v.tobytes())
    return _MEASURED.get(key, lambda: float(measure(v)))


def largest_face_area(vertices) -> float:
    """Area (m^2) of the largest planar face of the convex hull of ``vertices``."""
    return _measured("area", vertices, lambda v: ph.faces(v).areas.max())


def _volume(vertices) -> float:
    """Volume (m^3) of the convex hull of ``vertices``."""
    return _measured("volume", vertices, lambda v: ph.volume_centroid(v)[0])


def critical_step(blocks, materials) -> tuple[float, dict]:
    """(dt_crit in s, details) for blocks (list of dicts with vertices, role, material)
    and resolved materials (dicts with density, kn, damping)."""
    worst = None
    for b in blocks:
        if b["role"] != "free":
            continue
        m = materials[b["material"]]
        vol = sum(_volume(p) for p in b.get("parts", [b["vertices"]]))
        mass = m["density"] * vol
        k = 4.0 * m["kn"] * largest_face_area(b["vertices"])
        dt = law.critical_time_step(mass, k, m["damping"])
        if worst is None or dt < worst[0]:
            worst = (dt, {"block": b["id"], "mass_kg": mass, "stiffness_N_per_m": k,
                          "damping": m["damping"]})
    if worst is None:
        raise ValueError("no free block")
    return worst


def step_count_check(dt: float, duration: float, where: str, detail: dict | None = None) -> float:
    """Number of steps duration / dt (s / s); raises CaseError naming dt, the steps and the
    critical block (``detail`` from ``critical_step``) when it exceeds MAX_STEPS or dt is
    not a positive number."""
    steps = duration / dt if dt > 0 and math.isfinite(dt) else math.inf
    if steps <= MAX_STEPS:
        return steps
    block = ""
    if detail:
        block = (f"; the critical step is set by block {detail['block']} (mass {detail['mass_kg']:.3g} kg, "
                 f"contact stiffness {detail['stiffness_N_per_m']:.3g} N/m): check its size and its material's "
                 "density and kn")
    raise CaseError(f"{where}: the time step {dt:.3g} s over {duration:g} s simulated gives {steps:.3g} steps, more "
                    f"than {MAX_STEPS:.0e} (about 2 days at 3 ms per step){block}")
