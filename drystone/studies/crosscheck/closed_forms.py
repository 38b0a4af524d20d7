"""Rigid-body references of the cross-check cases (plain numpy/scipy; SI units, degrees).

* ``toppling_deg(b, h)``: a rigid block of base b (along the tilt) and height h on a rigid
  tilting plane, friction high enough not to slide (mu > b/h), topples at atan(b/h).
* ``rocking_history``: the same block under a load programme (``drystone.model.loading``:
  gravity ramp and tilt), by its rigid rocking equation about the downhill toe,
      I_toe phi'' = m a(t) . dr/dphi,   I_toe = m (b^2 + h^2) / 3,
  with r(phi) the centroid relative to the toe (rotated by phi towards the tilt) and a(t)
  the body acceleration of the programme; phi stays 0 while the moment does not lift the
  heel (a unilateral, rigid contact; no sliding, no bouncing). Its centroid history, read
  with the package's collapse rule (``drystone.mechanics.collapse.onset``: the onset of a motion of
  5 mm per degree of tilt), gives the angle a rigid engine must report with that rule:
  atan(b/h) plus the time the run-away takes to reach that rate (the rule's lag).
* ``half_sine_slide(A, T, mu, g)``: a rigid block on a base whose acceleration is the
  half-sine pulse a_b(t) = -A sin(pi t / T) for 0 <= t <= T (0 after; the package's sine
  excitation started from rest, ``start = "rest"``, run for half a period), Coulomb
  friction mu, rigid-plastic: the block slides relative to the base, u'' = -a_b - mu g
  sign(u'), from t1 = (T/pi) asin(mu g / A) (A > mu g) until its relative velocity
  w(t) = (A T/pi)(cos(pi t1/T) - cos(pi t/T)) - mu g (t - t1) (t <= T) returns to zero; after
  the pulse w decreases at mu g. Closed-form slide U(t2) (the stop time t2 is the root of
  w, explicit when the block is still sliding at T).
* ``rigid_plastic_slide(a_b, t_end, mu, g)``: the same rigid-plastic block under any base
  acceleration a_b(t) (one direction), integrated with a fine step: the pulse *as the
  engines apply it* (the package's sine excitation is sampled at 64 points per period and
  linearly interpolated between them; the chords lie inside the sine, so the applied
  pulse is slightly weaker than the continuous one and the slide ~0.4 % shorter).
"""
from __future__ import annotations

import math

import numpy as np

from drystone.mechanics import analytic, collapse
from drystone.units import GRAVITY


def toppling_deg(b: float, h: float) -> float:
    """atan(b/h) in degrees (``drystone.mechanics.analytic.rigid_toppling_tilt_deg``)."""
    return analytic.rigid_toppling_tilt_deg(b, h)


def rocking_history(b: float, h: float, prog, towards, t_end: float, interval: float, dt: float = 1e-4,
                    threshold: float | None = None) -> dict:
    """Rigid rocking of a b x h block (b along ``towards``) under ``prog`` (a
    ``drystone.model.loading.LoadProgramme``) from t = 0 to ``t_end`` (s), integrated by RK4 with
    step ``dt`` (s); samples every ``interval`` (s) as the package records them:
    ``{"t", "tilt_deg", "pos" (n, 1, 3) centroid relative to its start, "phi",
    "detected_time_s"}`` (the first sample where the centroid moved more than
    ``threshold``, default b/2 as the package's collapse threshold; else t_end)."""
    d = np.asarray(towards, float)
    z = np.array([0.0, 0.0, 1.0])
    i_toe = (b * b + h * h) / 3.0  # per unit mass

    def r(phi):
        return ((-0.5 * b * math.cos(phi) + 0.5 * h * math.sin(phi)) * d
                + (0.5 * b * math.sin(phi) + 0.5 * h * math.cos(phi)) * z)

    def drdphi(phi):
        return ((0.5 * b * math.sin(phi) + 0.5 * h * math.cos(phi)) * d
                + (0.5 * b * math.cos(phi) - 0.5 * h * math.sin(phi)) * z)

    def acc(t, phi):
        return float(prog.body_acceleration(t) @ drdphi(phi)) / i_toe

    def f(t, y):
        phi, om = y
        a = acc(t, phi)
        if phi <= 0.0 and om <= 0.0 and a <= 0.0:  # resting on its base: the contact holds it
            return np.zeros(2)
        return np.array([om, a])

    thr = 0.5 * b if threshold is None else threshold
    n = int(round(t_end / dt))
    every = max(1, int(round(interval / dt)))
    y = np.zeros(2)
    r0 = r(0.0)
    ts, tilts, pos, phis = [0.0], [prog.tilt_deg(0.0)], [np.zeros(3)], [0.0]
    # the block rests on its base (phi = 0, nothing to integrate) until the moment about the
    # toe first turns positive: samples up to the last one before that are recorded as such
    k0 = 0
    while k0 + every <= n and acc((k0 + every) * dt, 0.0) <= 0.0:
        k0 += every
        ts.append(k0 * dt)
        tilts.append(prog.tilt_deg(k0 * dt))
        pos.append(np.zeros(3))
        phis.append(0.0)
    detected = None
    for k in range(k0, n):
        t = k * dt
        k1 = f(t, y)
        k2 = f(t + dt / 2, y + dt / 2 * k1)
        k3 = f(t + dt / 2, y + dt / 2 * k2)
        k4 = f(t + dt, y + dt * k3)
        y = y + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if y[0] < 0.0:  # back on its base (rigid, no bounce)
            y = np.zeros(2)
        if (k + 1) % every == 0:
            tt = (k + 1) * dt
            p = r(y[0]) - r0
            ts.append(tt)
            tilts.append(prog.tilt_deg(tt))
            pos.append(p)
            phis.append(y[0])
            if detected is None and np.linalg.norm(p) > thr:
                detected = tt
                break
    return {"t": np.array(ts), "tilt_deg": np.array(tilts), "pos": np.array(pos)[:, None, :], "phi": np.array(phis),
            "detected_time_s": detected if detected is not None else ts[-1]}


def rocking_onset_deg(b: float, h: float, prog, towards, t_end: float, interval: float,
                      rate_m_per_deg: float = collapse.RATE_M_PER_DEG, window_deg: float = collapse.WINDOW_DEG,
                      dt: float = 1e-4) -> float | None:
    """The collapse angle the package's rule reads on the rigid rocking history (deg)."""
    hist = rocking_history(b, h, prog, towards, t_end, interval, dt)
    on = collapse.onset(hist["tilt_deg"], hist["pos"], hist["t"], hist["detected_time_s"], rate_m_per_deg, window_deg)
    return None if on is None else on["angle_deg"]


def half_sine_slide(amplitude: float, duration: float, mu: float, g: float = GRAVITY) -> dict:
    """Rigid-plastic slide (m) of a block under the half-sine base pulse (module docstring):
    ``{"slide_m", "start_s", "stop_s", "peak_velocity_m_s"}`` (times from the pulse's start).
    No slide (0) when amplitude <= mu g."""
    A, T, mg = float(amplitude), float(duration), float(mu) * float(g)
    if A <= mg:
        return {"slide_m": 0.0, "start_s": None, "stop_s": None, "peak_velocity_m_s": 0.0}
    w_ = math.pi / T
    t1 = math.asin(mg / A) / w_
    c1 = math.cos(w_ * t1)

    def w(t):  # relative velocity during the pulse
        return A / w_ * (c1 - math.cos(w_ * t)) - mg * (t - t1)

    def u(t):  # relative displacement during the pulse
        return A / w_ * (c1 * (t - t1) - (math.sin(w_ * t) - math.sin(w_ * t1)) / w_) - 0.5 * mg * (t - t1) ** 2

    t_peak = T - t1  # a_b back to mu g: the largest relative velocity
    v_peak = w(t_peak)
    w_end = w(T)
    if w_end > 0.0:  # still sliding when the pulse ends: decelerates at mu g
        t2 = T + w_end / mg
        slide = u(T) + w_end * (t2 - T) - 0.5 * mg * (t2 - T) ** 2
    else:  # stops during the pulse, on its descending half: the root of w in (t_peak, T]
        from scipy.optimize import brentq
        t2 = brentq(w, t_peak, T, xtol=1e-14)
        slide = u(t2)
    return {"slide_m": float(slide), "start_s": float(t1), "stop_s": float(t2), "peak_velocity_m_s": float(v_peak)}


def rigid_plastic_slide(a_b, t_end: float, mu: float, g: float = GRAVITY, dt: float = 1e-5) -> dict:
    """Slide (m) of a rigid-plastic block under the base acceleration ``a_b(t)`` (m/s^2,
    a function of time from 0) along one axis, from rest, until ``t_end`` (s): relative
    acceleration -a_b - mu g sign(w) while sliding (w the relative velocity); it starts
    when |a_b| > mu g and stops when w crosses zero with |a_b| <= mu g (the crossing
    located by linear interpolation within the step). Midpoint rule, step ``dt``:
    second-order accurate. Returns ``{"slide_m", "start_s", "stop_s", "peak_velocity_m_s"}``
    (times of the first slide)."""
    mg = float(mu) * float(g)
    n = int(math.ceil(t_end / dt))
    u = w = 0.0
    start = stop = None
    peak = 0.0
    for k in range(n):
        t = k * dt
        am = a_b(t + 0.5 * dt)
        if w == 0.0:
            if abs(am) <= mg:
                continue
            s = -math.copysign(1.0, am)
            if start is None:
                start = t
        else:
            s = math.copysign(1.0, w)
        w_new = w + (-am - mg * s) * dt
        if w != 0.0 and w_new * w < 0.0:  # the relative velocity reaches zero within the step
            f = w / (w - w_new)
            u += 0.5 * w * f * dt
            w = 0.0
            if stop is None:
                stop = t + f * dt
            continue
        u += 0.5 * (w + w_new) * dt
        w = w_new
        peak = max(peak, abs(w))
    return {"slide_m": float(u), "start_s": start, "stop_s": stop, "peak_velocity_m_s": float(peak)}
