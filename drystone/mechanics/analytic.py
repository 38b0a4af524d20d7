"""Closed-form references that the simulations are checked against (no YADE).

Units SI; angles returned in degrees.
"""
from __future__ import annotations

import math

import numpy as np

from drystone.units import GRAVITY


def sliding_tilt_deg(mu: float) -> float:
    """Tilt at which a block slides on a tilting plane: atan(mu)."""
    return math.degrees(math.atan(mu))


def rigid_toppling_tilt_deg(b: float, h: float) -> float:
    """Tilt at which a rigid block of base b (along the tilt) and height h topples on a rigid
    plane: atan(b / h)."""
    return math.degrees(math.atan2(b, h))


def toppling_tilt_deg(b: float, h: float, t: float, density: float, kn: float, g: float = GRAVITY) -> float:
    """Tilt (deg) at which a rigid rectangular block (b along the tilt, thickness t, height
    h) topples on a penalty (Winkler) contact of stiffness kn per unit area (N/m^3): the
    stone of ``stone_toppling_tilt_deg`` with its centroid at (b/2, h/2) from its toe. As
    kn grows this tends to atan(b/h), slowly: the deficit scales as (rho g h / kn)^(1/3)
    (at kn = 2e8 N/m^3 a 0.2 x 0.4 m block topples 3.4 deg early)."""
    return stone_toppling_tilt_deg(0.5 * b, 0.5 * h, b, t, density * g * b * t * h, kn)


def stone_toppling_tilt_deg(d: float, e: float, footprint: float, t: float, weight: float, kn: float) -> float:
    """Tilt (deg) at which a rigid stone of any shape topples about its downhill toe on a
    penalty (Winkler) contact of stiffness kn (N/m^3), its base a rectangle ``footprint``
    long (along the tilt) and t wide, its centroid d along the tilt from the toe and e
    above the base (m), its weight W (N). The rigid limit is atan(d / e).

    Past the kern the joint opens; with the stone rocked by phi about its toe the contact
    width is a = sqrt(2 N / (kn t phi)), N = W cos(theta), the pressure resultant sits at
    a/3 from the toe, and moment equilibrium about it gives
        tan(theta) = [d cos(phi) - e sin(phi) - a/3] / [d sin(phi) + e cos(phi)].
    The stone topples at the largest theta for which some phi satisfies it.
    """
    w = weight

    def theta(phi: float) -> float:
        th = math.atan2(d, e)
        for _ in range(60):  # fixed point on the weak dependence of a on cos(theta)
            a = math.sqrt(2.0 * w * math.cos(th) / (kn * t * phi))
            if a > footprint:
                return -math.inf  # the joint is still closed: not the toppling branch
            num = d * math.cos(phi) - e * math.sin(phi) - a / 3.0
            den = d * math.sin(phi) + e * math.cos(phi)
            th = math.atan2(num, den)
        return th

    phis = np.logspace(-9, -0.3, 3000)
    vals = np.array([theta(p) for p in phis])
    k = int(np.argmax(vals))
    lo, hi = phis[max(k - 1, 0)], phis[min(k + 1, len(phis) - 1)]
    for _ in range(60):  # golden-section refinement of the maximum
        m1, m2 = lo + 0.382 * (hi - lo), lo + 0.618 * (hi - lo)
        if theta(m1) < theta(m2):
            lo = m1
        else:
            hi = m2
    return math.degrees(theta(0.5 * (lo + hi)))
