"""Intensity measures (IMs) of a run: PGA, PGV and Sa(T1) of its record as applied.

"As applied" is what the runner gives the wall: the record file, cut to the run's record
duration and scaled to the run's PGA, through the same function the runner calls
(``motions.excitation.record_for_stage``). Then (``motions.intensity``):

* ``pga_g``: max|a| in g (exact to rounding);
* ``pgv_m_s``: max|v| (m/s), v the trapezoid integral from rest of the samples as applied
  (no baseline correction);
* ``sa_t1_g``: 5 %-damped pseudo-spectral acceleration at the wall's first period T1, in g.

All three scale with the PGA (a record scaled by s has s times each).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

from drystone.motions import excitation, intensity, processing


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
