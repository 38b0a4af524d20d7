"""Intensity measures of one acceleration record (``Record``: acc in m/s^2 at step dt in s).

Units: SI in every value, g only where the name says ``_g`` (g = ``drystone.units.G_STANDARD``
= 9.80665 m/s^2).

* ``pga(r)`` (m/s^2): max |a|.
* ``velocity(r)`` (m/s), ``pgv(r)`` (m/s), ``displacement(r)`` (m), ``pgd(r)`` (m): the
  record integrated from rest by the trapezoid rule (scipy ``cumulative_trapezoid``) **as
  the simulation applies it**: no baseline correction, because the runner applies the
  samples unchanged (``motions.excitation``) and the PEER records of the FEMA P695 sets are
  already baseline-corrected and filtered by PEER (their trapezoid PGV equals the set's
  ``PGVmax`` to its 1 cm/s rounding for 20 of the 22 far-field records: tests/test_intensity.py).
  ``drift_order=k`` instead uses ``motions.processing.integrate(r, poly_order=k)`` (the
  package's drift control for displacement-driven platforms: the polynomial t^2..t^k fitted
  to the displacement removed) for raw records that drift.
* ``arias(r)`` (m/s): Arias intensity I_a = pi / (2 g) * integral a^2 dt (trapezoid).
* ``significant_duration(r)`` (s): D5-95 = t95 - t5 of the cumulative a^2
  (``motions.analysis.arias_times``).
* ``psa(r, periods, damping=0.05)`` (m/s^2): pseudo-spectral acceleration omega_n^2 max|u|
  of a linear oscillator (``motions.spectra.response_spectrum``: exact for a piecewise-
  linear record); ``psa_g`` in g.
* ``measures(r, periods)``: all of the above as a JSON-ready dict (units in the key names).
"""
from __future__ import annotations

import math

import numpy as np
from scipy import integrate as sint

from drystone.motions import analysis, processing, spectra
from drystone.motions.record import G, Record

#: periods (s) at which ``measures`` (and ``python -m drystone.motions spectrum``) report Sa
REPORT_PERIODS_S = (0.1, 0.2, 0.3, 0.5, 1.0, 2.0)
#: damping ratio of the response spectrum
DAMPING = 0.05


def pga(r: Record) -> float:
    """Peak ground acceleration max|a| (m/s^2)."""
    return r.pga


def _kinematics(r: Record, drift_order: int | None) -> tuple[np.ndarray, np.ndarray]:
    if drift_order is not None:
        k = processing.integrate(r, poly_order=drift_order)
        return k.velocity, k.displacement
    v = sint.cumulative_trapezoid(r.acc, dx=r.dt, initial=0.0)
    return v, sint.cumulative_trapezoid(v, dx=r.dt, initial=0.0)


def velocity(r: Record, drift_order: int | None = None) -> np.ndarray:
    """Ground velocity (m/s) from rest at the sample times (module docstring)."""
    return _kinematics(r, drift_order)[0]


def displacement(r: Record, drift_order: int | None = None) -> np.ndarray:
    """Ground displacement (m) from rest at the sample times (module docstring)."""
    return _kinematics(r, drift_order)[1]


def pgv(r: Record, drift_order: int | None = None) -> float:
    """Peak ground velocity max|v| (m/s)."""
    return float(np.abs(velocity(r, drift_order)).max())


def pgd(r: Record, drift_order: int | None = None) -> float:
    """Peak ground displacement max|d| (m); sensitive to any drift of the record."""
    return float(np.abs(displacement(r, drift_order)).max())


def arias(r: Record) -> float:
    """Arias intensity pi / (2 g) * integral a^2 dt (m/s), trapezoid rule."""
    return float(math.pi / (2 * G) * sint.trapezoid(r.acc ** 2, dx=r.dt))


def significant_duration(r: Record) -> float:
    """D5-95 (s): time between 5 % and 95 % of the cumulative a^2."""
    t5, t95 = analysis.arias_times(r)
    return t95 - t5


def psa(r: Record, periods, damping: float = DAMPING) -> np.ndarray:
    """Pseudo-spectral acceleration (m/s^2) at ``periods`` (s), damping ratio ``damping``."""
    periods = np.atleast_1d(np.asarray(periods, float))
    if not np.all(np.isfinite(periods)) or np.any(periods <= 0):
        raise ValueError(f"periods must be positive numbers (s), got {periods.tolist()}")
    return spectra.response_spectrum(r.acc, r.dt, periods, damping)


def psa_g(r: Record, periods, damping: float = DAMPING) -> np.ndarray:
    """Pseudo-spectral acceleration in g at ``periods`` (s)."""
    return psa(r, periods, damping) / G


def measures(r: Record, periods=REPORT_PERIODS_S, damping: float = DAMPING) -> dict:
    """PGA, PGV, PGD, Arias intensity, D5-95 and Sa at ``periods``; units in the key names."""
    t5, t95 = analysis.arias_times(r)
    v, d = _kinematics(r, None)
    periods = [float(p) for p in periods]
    return {"pga_g": r.pga_g, "pga_m_s2": r.pga, "pgv_m_s": float(np.abs(v).max()),
            "pgd_m": float(np.abs(d).max()), "arias_m_s": arias(r), "t5_s": t5, "t95_s": t95,
            "significant_duration_s": t95 - t5,
            "sa": {"periods_s": periods, "psa_g": psa_g(r, periods, damping).tolist(), "damping": damping,
                   "definition": "pseudo-spectral acceleration omega_n^2 max|u| of a linear oscillator, in g"},
            "velocity_from": "the samples as applied, trapezoid from rest, no baseline correction"}
