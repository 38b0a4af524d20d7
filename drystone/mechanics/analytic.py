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
    h) topples on a penalty (Winkler) contact of stiffness kn per unit area (N/m^3).

    Past the kern the joint opens; with the block rocked by phi about its toe the contact
    width is a = sqrt(2 N / (kn t phi)), N = W cos(theta), the pressure resultant sits at
    a/3 from the toe, and moment equilibrium about it gives
        tan(theta) = [(b/2) cos(phi) - (h/2) sin(phi) - a/3] / [(b/2) sin(phi) + (h/2) cos(phi)].
    The block topples at the largest theta for which some phi satisfies it. As kn grows
    this tends to atan(b/h), slowly: the deficit scales as (rho g h / kn)^(1/3) (at
    kn = 2e8 N/m^3 a 0.2 x 0.4 m block topples 3.4 deg early).
    """
    w = density * g * b * t * h

    def theta(phi: float) -> float:
        th = math.atan2(b, h)
        for _ in range(60):  # fixed point on the weak dependence of a on cos(theta)
            a = math.sqrt(2.0 * w * math.cos(th) / (kn * t * phi))
            if a > b:
                return -math.inf  # the joint is still closed: not the toppling branch
            num = 0.5 * b * math.cos(phi) - 0.5 * h * math.sin(phi) - a / 3.0
            den = 0.5 * b * math.sin(phi) + 0.5 * h * math.cos(phi)
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
