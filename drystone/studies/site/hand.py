"""Hand checks of the retained wall: its free stones taken as ONE rigid body on what holds
them (the fixed course and the platform), under the soil's pseudo-static load
(drystone/mechanics/earth_pressure.py, integrated over the same back faces as the runs'
load) and its own weight, in the field of a platform tilted by theta towards the open side
(k_h = sin theta, 1 - k_v = cos theta: drystone/model/loads.py) or with a water table.

* sliding on a horizontal bed with friction mu: the outward force (the stones' weight
  component W sin theta plus the soil's horizontal thrust) against mu times the normal force
  (W cos theta plus the soil's downward drag);
* toppling about the front edge of the body's base (the line at the front face, y_front, and
  the lowest point of the free stones, z_pivot): the soil's and the weight's moments about it.

Results: the tilt (deg) and the water level (m above the platform) at which each margin
reaches zero (``critical``). A rigid monolith is an upper bound of a dry-stone wall's
strength against these two mechanisms only (a wall can fail by a part, or by a mechanism
between the two), and a lower one where its stones interlock with the held side stones: an
order of magnitude for the runs, not a validation. Units: N, m, rad inside; deg for tilts.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from drystone.kept import Kept
from drystone.mechanics import earth_pressure as ep
from drystone.units import GRAVITY


@dataclass(frozen=True)
class Body:
    """The free stones as one rigid body: weight (N), centroid (m), the soil's load integrated
    over their back faces (``ep.WallLoads``), the pivot of toppling (the front face's
    coordinate along ``outward`` and the base's elevation, m), the outward horizontal unit
    vector (from the soil to the wall's front) and the stones ({id: parts})."""

    weight: float
    centroid: np.ndarray
    soil: ep.EarthPressure
    loads: ep.WallLoads
    pivot: tuple
    outward: np.ndarray
    stones: dict


def body(blocks: dict, soil: ep.EarthPressure) -> Body:
    """The free stones of a block-file dict as one body (module docstring); weight at the
    simulations' default gravity (drystone.units.GRAVITY)."""
    from drystone.geometry import blockfile as bf

    bs = bf.parse(blocks, blocks.get("name", "<geometry>"), check_overlaps=False)
    free = [b for b in bs.blocks if b.role == "free"]
    mass = np.array([bs.mass(b.id) for b in free])
    cen = (mass[:, None] * np.array([b.centroid for b in free])).sum(axis=0) / mass.sum()
    stones = {b.id: [np.asarray(p, float) for p in b.parts] for b in free}
    out = -soil.horizontal
    pts = np.vstack([b.points for b in free])
    front = float((pts @ out).max())  # the front face's coordinate along the outward direction
    return Body(float(mass.sum() * GRAVITY), cen, soil, ep.wall_loads(stones, soil),
                (front, float(pts[:, 2].min())), out, stones)


def _soil_force(b: Body, theta: float) -> tuple[np.ndarray, float]:
    """The soil's total force (N, platform frame) and its moment (N m) about the pivot line,
    positive outwards (toppling), at a tilt theta (rad) towards the open side."""
    F, M = b.loads.at(math.sin(theta), 1.0 - math.cos(theta))
    f, m = F[0], M[0]
    axis = np.cross(np.array([0.0, 0.0, 1.0]), b.outward)  # rotation axis of an outward topple
    pivot = b.pivot[0] * b.outward + np.array([0.0, 0.0, b.pivot[1]])
    r = b.loads.centroids - pivot
    r = r - np.outer(r @ axis, axis)  # in the plane normal to the axis
    moment = float(np.sum(np.cross(r, f) @ axis) + np.sum(m @ axis))
    return f.sum(axis=0), moment


def margins(b: Body, theta: float, mu: float) -> tuple[float, float]:
    """(sliding, toppling) margins at a tilt theta (rad): driving minus resisting, N and N m;
    the body slides or topples where a margin is positive."""
    f, m_soil = _soil_force(b, theta)
    w = b.weight
    out_force = w * math.sin(theta) + float(f @ b.outward)
    normal = w * math.cos(theta) - float(f[2])
    lever_h = float(b.centroid @ b.outward) - b.pivot[0]  # the centroid behind the front edge: < 0
    lever_v = float(b.centroid[2]) - b.pivot[1]
    m_weight = w * math.sin(theta) * lever_v + w * math.cos(theta) * lever_h  # outwards positive
    return out_force - mu * normal, m_soil + m_weight


def _root(fun, lo: float, hi: float) -> float:
    """The root of a margin increasing from ``lo`` to ``hi``: ``lo`` when already positive
    there, inf when still negative at ``hi``."""
    if fun(lo) >= 0.0:
        return lo
    if fun(hi) < 0.0:
        return math.inf
    return brentq(fun, lo, hi, xtol=1e-12)


def critical_tilt(b: Body, mu: float) -> dict:
    """The tilts (deg) at which the body starts to slide and to topple, up to Mononobe-Okabe's
    limit theta = phi - beta."""
    top = b.soil.phi - b.soil.beta - 1e-9
    return {"slide_deg": math.degrees(_root(lambda t: margins(b, t, mu)[0], 0.0, top)),
            "topple_deg": math.degrees(_root(lambda t: margins(b, t, mu)[1], 0.0, top))}


def critical_water(b: Body, mu: float) -> dict:
    """The water levels (m above the platform) at which the body, untilted, starts to slide
    and to topple, between the soil's base and its top."""
    def at(z, k):
        soil = replace(b.soil, water_level=z)
        return margins(replace(b, soil=soil, loads=ep.wall_loads(b.stones, soil)), 0.0, mu)[k]

    return {"slide_m": _root(lambda z: at(z, 0), b.soil.z_base, b.soil.z_top),
            "topple_m": _root(lambda z: at(z, 1), b.soil.z_base, b.soil.z_top)}


def retained(case=None) -> tuple[Body, float]:
    """The body of the retained case's free stones under its [[loads]] soil (resolved as a
    run resolves it: drystone.model.loads) and the stones' friction coefficient."""
    import tempfile
    from pathlib import Path

    from drystone import runner
    from drystone.model import case as casemod
    from drystone.model.loads import soil_from_params
    from drystone.studies.site import plan as planmod

    path = case or planmod.record_case("retained")
    with tempfile.TemporaryDirectory() as tmp:
        spec = runner.resolve(casemod.load(path), str(path), Path(tmp))
        blocks = json.loads((Path(tmp) / "geometry.json").read_text())
    soil = soil_from_params(spec["loads"][0]["params"])
    mus = {m["mu"] for m in spec["materials"].values()}
    if len(mus) != 1:
        raise ValueError(f"{path}: the hand check needs one friction coefficient, got {sorted(mus)}")
    return body(blocks, soil), mus.pop()


#: this process's hand checks by their case file and its bytes (``summary``): a study's report
#: written again gives the same check
_KEPT = Kept(8)


def summary(case=None) -> dict:
    """The retained wall's hand check: weight (N), friction, critical tilts (deg) and water
    levels (m)."""
    from pathlib import Path

    from drystone.studies.site import plan as planmod

    path = Path(case or planmod.record_case("retained"))
    key = (str(path.resolve()), path.read_bytes())

    def check():
        b, mu = retained(path)
        return {"weight_N": b.weight, "mu": mu, "pivot_m": list(b.pivot), **critical_tilt(b, mu),
                **critical_water(b, mu)}

    return _KEPT.get(key, check)
