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


def rocking_pulse(a_p: float, omega_p: float, b: float, h: float, r: float | None = None, g: float = GRAVITY,
                  t_after: float = 6.0, shape: str = "sine") -> dict:
    """Rigid rocking block under a one-sine acceleration pulse (Zhang & Makris, J. Eng. Mech.
    2001, "Rocking response of free-standing blocks under cycloidal pulses", their type-A
    pulse): base acceleration u_g''(t) = a_p sin(omega_p t) for 0 <= t <= 2 pi / omega_p,
    0 after. A rigid block of width b (along the shaking) and height h, no sliding, on a
    rigid base (their Eq. 2, Housner's):

        theta'' = -p^2 [sin(alpha sgn(theta) - theta) + (u_g''/g) cos(alpha sgn(theta) - theta)],

    p = sqrt(3 g / (4 R)), R = sqrt(b^2 + h^2) / 2, alpha = atan(b / h); rocking starts when
    |u_g''| > g tan(alpha) (the block rocks away from the acceleration); at each impact
    (theta through 0) the angular velocity is multiplied by ``r`` (default Housner's
    1 - 1.5 sin^2 alpha). Integrated (DOP853, relative tolerance 1e-10) until t_after (s)
    past the pulse, the pulse's end a step's end and the extremes of theta found as events
    (theta' = 0); returns {"overturned": bool (|theta| reached pi/2), "impacts",
    "max_theta_rad", "time_s" (of the overturn, or None)}. SI units. ``shape`` = "rectangle":
    u_g''(t) = a_p for 0 <= t <= pi / omega_p instead (Housner 1963's rectangular pulse, whose
    linearised overturning amplitude is g alpha / (1 - exp(-p t_1)), ``rectangle_overturning``)."""
    from scipy.integrate import solve_ivp

    alpha = math.atan2(b, h)
    p2 = 3.0 * g / (2.0 * math.hypot(b, h))
    r = 1.0 - 1.5 * math.sin(alpha) ** 2 if r is None else float(r)
    if shape not in ("sine", "rectangle"):
        raise ValueError(f"shape must be 'sine' or 'rectangle', got {shape!r}")
    tp = (2.0 if shape == "sine" else 1.0) * math.pi / omega_p

    def ag(t):
        if t > tp:
            return 0.0
        return a_p * math.sin(omega_p * t) if shape == "sine" else a_p

    if a_p <= g * math.tan(alpha):
        return {"overturned": False, "impacts": 0, "max_theta_rad": 0.0, "time_s": None}
    # rocking starts at the first time |u_g''| exceeds g tan(alpha): in the first half-sine
    t0 = math.asin(g * math.tan(alpha) / a_p) / omega_p if shape == "sine" else 0.0
    sgn = -1.0 if ag(t0 + 1e-12) > 0 else 1.0
    y, t, impacts, top = np.array([0.0, 0.0]), t0, 0, 0.0
    t_end = tp + t_after

    def f(tt, yy, s):
        th = yy[0]
        return [yy[1], -p2 * (math.sin(alpha * s - th) + ag(tt) / g * math.cos(alpha * s - th))]

    while t < t_end:
        def impact(tt, yy, s=sgn):
            return yy[0]
        impact.terminal, impact.direction = True, (-1.0 if sgn > 0 else 1.0)

        def over(tt, yy, s=sgn):
            return abs(yy[0]) - 0.5 * math.pi
        over.terminal, over.direction = True, 1.0

        def peak(tt, yy, s=sgn):  # theta' = 0: the rocking's extremes, found exactly
            return yy[1]
        # the pulse's end is a segment's end (the forcing is smooth within each); the first
        # instants of a rocking phase start at theta = 0: nudge past the event
        t_stop = tp if t < tp else t_end
        sol = solve_ivp(f, (t, t_stop), y, args=(sgn,), method="DOP853", rtol=1e-10, atol=1e-12,
                        events=(impact, over, peak), first_step=1e-6)
        top = max(top, float(np.max(np.abs(sol.y[0]))))
        if sol.t_events[2].size:
            top = max(top, float(np.max(np.abs(sol.y_events[2][:, 0]))))
        if sol.t_events[1].size:
            return {"overturned": True, "impacts": impacts, "max_theta_rad": 0.5 * math.pi,
                    "time_s": float(sol.t_events[1][0])}
        if not sol.t_events[0].size:
            if t_stop < t_end:  # the pulse is over: the same rocking phase goes on
                t, y = t_stop, sol.y[:, -1]
                continue
            break
        t = float(sol.t_events[0][0])
        om = float(sol.y_events[0][0][1]) * r
        impacts += 1
        if abs(om) < 1e-9:  # the block comes to rest; a later pulse half may start it again
            if t < tp and abs(ag(t)) > g * math.tan(alpha):
                sgn = -1.0 if ag(t) > 0 else 1.0
                y = np.array([0.0, 0.0])
                continue
            break
        sgn = -sgn
        y = np.array([0.0, om])
    return {"overturned": False, "impacts": impacts, "max_theta_rad": top, "time_s": None}


def rectangle_overturning(t1: float, b: float, h: float, g: float = GRAVITY) -> float:
    """Least amplitude (m/s^2) of a rectangular base pulse of duration ``t1`` (s) that
    overturns a slender rigid block (b wide, h tall) without an impact, from the linearised
    rocking equation theta'' = p^2 (theta - alpha + a/g): theta = beta (cosh pt - 1) with
    beta = a/g - alpha during the pulse; after it the block overturns when it is beyond the
    separatrix, theta' >= p (alpha - theta), i.e. beta (e^{p t1} - 1) >= alpha:
    a = g alpha / (1 - e^{-p t1}) (Housner 1963). Exact as alpha -> 0."""
    alpha = math.atan2(b, h)
    p = math.sqrt(3.0 * g / (2.0 * math.hypot(b, h)))
    return g * alpha / (1.0 - math.exp(-p * t1))


def min_overturning_pulse(omega_p: float, b: float, h: float, r: float | None = None, g: float = GRAVITY,
                          hi_g: float = 5.0, tol_g: float = 1e-4, levels: int = 200,
                          shape: str = "sine") -> float | None:
    """The least amplitude a_p (in g) of the one-sine pulse of ``rocking_pulse`` that
    overturns the rigid block (Zhang & Makris 2001's minimum overturning acceleration):
    a scan of ``levels`` amplitudes from g tan(alpha) to ``hi_g`` (the overturning region
    is not an interval: a block overturned at one amplitude may survive a larger one), then
    a bisection of the first overturning level's interval to ``tol_g``. None when no
    amplitude up to hi_g overturns it."""
    lo0 = math.tan(math.atan2(b, h))
    grid = np.linspace(lo0, hi_g, levels)
    hit = next((k for k, a in enumerate(grid) if rocking_pulse(a * g, omega_p, b, h, r, g, shape=shape)["overturned"]),
               None)
    if hit is None:
        return None
    lo, hi = (grid[hit - 1] if hit else lo0), grid[hit]
    while hi - lo > tol_g:
        mid = 0.5 * (lo + hi)
        if rocking_pulse(mid * g, omega_p, b, h, r, g, shape=shape)["overturned"]:
            hi = mid
        else:
            lo = mid
    return float(hi)
