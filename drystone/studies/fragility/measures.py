"""Intensity measures of each fragility run (generic part: drystone/analyses/measures.py); T1 of the wall.

"As applied" is what the runner gives the wall: the plan's record file, cut to the run's
record duration and scaled to the stripe's PGA, through the same function the runner
calls (``motions.excitation.record_for_stage``). Then (``motions.intensity``):

* ``pga_g``: max|a| in g, the stripe value (exact to rounding);
* ``pgv_m_s``: max|v| (m/s), v the trapezoid integral from rest of the samples as applied
  (no baseline correction: the PEER records are baseline-corrected already);
* ``sa_t1_g``: 5 %-damped pseudo-spectral acceleration at the wall's first period T1, in g.

T1 (``first_period``): 1 / f1 with f1 the wall's own frequency measured by the
Sacsayhuaman identification (``studies.sacsayhuaman.study.wall_frequency``: the strongest
coherent peak of the transfer function base -> control point A in the reference white-noise
run, results/sacsayhuaman_white_noise/seed_0) when that run is in ``results/``; otherwise the
stated default ``DEFAULT_F1_HZ`` (ASSUMED in the report: not measured in this checkout).
T1 is that of the case's wall (K_n = 2e8 N/m^3); the runs draw K_n down to 5e7 N/m^3, for
which a linear wall would have a period up to 2 x longer (f ~ K_n^1/2): one T1 for every
run, as usual for Sa(T1), and the report says so.
"""
from __future__ import annotations

from drystone.analyses.measures import (DEFAULT, MEASURES, Measure, by_key, record_as_applied,  # noqa: F401
                                        run_measures)

#: f1 (Hz) when no identification run is present: the transfer-function peak of seed_0,
#: control point A (2.60 Hz, half-power damping 12.9 %) in the identification table of
#: docs/validation-sacsayhuaman.md (generated from results/sacsayhuaman/identification.md by an earlier
#: `python -m drystone.studies.sacsayhuaman identify`); the other amplitudes gave 2.59-2.63 Hz
DEFAULT_F1_HZ = 2.60
DEFAULT_F1_SOURCE = ("identification table of docs/validation-sacsayhuaman.md (transfer function base -> control point A, run seed_0: 2.60 Hz; "
                     "2.59-2.63 Hz at the other white-noise amplitudes), from an earlier "
                     "`python -m drystone.studies.sacsayhuaman identify`; not measured in this checkout")


def first_period(f1_hz: float | None = None) -> dict:
    """T1 (s) and where it comes from: ``f1_hz`` when given, else the identification run
    (measured), else ``DEFAULT_F1_HZ`` (assumed)."""
    if f1_hz is not None:
        return {"t1_s": 1.0 / float(f1_hz), "f1_hz": float(f1_hz), "measured": False, "source": "given"}
    try:
        from drystone.studies.sacsayhuaman import study as sacsay

        f = sacsay.wall_frequency()
    except (OSError, ValueError, KeyError, IndexError) as exc:  # an unreadable run: say so, use the default
        f, why = None, f"identification run unreadable ({type(exc).__name__}: {exc})"
    else:
        why = "no identification run in results/sacsayhuaman_white_noise/seed_0"
    if f:
        return {"t1_s": 1.0 / f, "f1_hz": float(f), "measured": True,
                "source": "measured: transfer function base -> control point A of results/sacsayhuaman_white_noise/"
                          "seed_0 (studies.sacsayhuaman.study.wall_frequency)"}
    return {"t1_s": 1.0 / DEFAULT_F1_HZ, "f1_hz": DEFAULT_F1_HZ, "measured": False,
            "source": f"ASSUMED ({why}): {DEFAULT_F1_SOURCE}"}
