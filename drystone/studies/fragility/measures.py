"""Intensity measures (IMs) of each fragility run: PGA, PGV and Sa(T1) of the record as applied.

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

import functools
from dataclasses import dataclass

from drystone.motions import excitation, intensity, processing

#: f1 (Hz) when no identification run is present: the transfer-function peak of seed_0,
#: control point A (2.60 Hz, half-power damping 12.9 %) in the identification table of
#: docs/validation-sacsayhuaman.md (generated from results/sacsayhuaman/identification.md by an earlier
#: `python -m drystone.studies.sacsayhuaman identify`); the other amplitudes gave 2.59-2.63 Hz
DEFAULT_F1_HZ = 2.60
DEFAULT_F1_SOURCE = ("identification table of docs/validation-sacsayhuaman.md (transfer function base -> control point A, run seed_0: 2.60 Hz; "
                     "2.59-2.63 Hz at the other white-noise amplitudes), from an earlier "
                     "`python -m drystone.studies.sacsayhuaman identify`; not measured in this checkout")


@dataclass(frozen=True)
class Measure:
    """One intensity measure: key in a run's row, symbol, unit, and what it is."""

    key: str
    symbol: str
    unit: str
    meaning: str


#: the IMs the study fits against, the default first
MEASURES = (Measure("pga_g", "PGA", "g", "peak ground acceleration of the scaled record"),
            Measure("pgv_m_s", "PGV", "m/s", "peak ground velocity: trapezoid integral of the scaled record from "
                                              "rest, no baseline correction"),
            Measure("sa_t1_g", "Sa(T1)", "g", "5 %-damped pseudo-spectral acceleration at the wall's first "
                                              "period T1"))
DEFAULT = "pga_g"


def by_key(key: str) -> Measure:
    for m in MEASURES:
        if m.key == key:
            return m
    raise KeyError(f"unknown intensity measure {key!r} (known: {', '.join(m.key for m in MEASURES)})")


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


@functools.lru_cache(maxsize=64)
def _record(path: str, duration_s: float | None):
    """The record of a run before scaling (cut as the stage cuts it), read once per file."""
    return excitation.record_for_stage({"motion": "record", "record": path, "duration": duration_s, "pga_g": None})


def record_as_applied(record_file: str, pga_g: float, duration_s: float | None = None):
    """The Record the runner applies: ``record_file`` cut to ``duration_s`` (s) and scaled to
    ``pga_g`` (g), as ``motions.excitation.record_for_stage`` does."""
    return processing.scale_to_pga(_record(str(record_file), duration_s), pga_g=pga_g)


def run_measures(record_file: str, pga_g: float, t1_s: float, duration_s: float | None = None) -> dict:
    """{pga_g (g), pgv_m_s (m/s), sa_t1_g (g)} of one run's record as applied."""
    r = record_as_applied(record_file, pga_g, duration_s)
    return {"pga_g": r.pga_g, "pgv_m_s": intensity.pgv(r), "sa_t1_g": float(intensity.psa_g(r, [t1_s])[0])}
