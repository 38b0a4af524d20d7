"""The record type: one component of base acceleration, uniformly sampled, with its metadata.

``Record.acc`` is in m/s^2 and ``Record.dt`` in s whatever the file said
(``units_in_file`` keeps what it declared). ``start_time`` (s) is the time of the first
sample relative to the start of the source file (non-zero after trimming), so
``time`` = start_time + k dt. Every operation that changes the samples returns a new
Record and appends a line to ``history``; ``scale_factor`` is the product of all
amplitude scalings applied since the file was read.

For the simulation: ``record.acc`` / ``record.dt``, ``record.interpolant()`` (a(t) by
linear interpolation, zero outside the record, t measured from the first sample),
``motions.processing.resample(record, dt)``, and ``record.metadata()`` (a JSON-ready
dict for provenance).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from drystone.units import G_STANDARD as G  # 1 g (m/s^2), for every conversion from or to g

#: factor to m/s^2 of each accepted unit name (lower case, spaces removed)
UNIT_FACTORS = {
    "m/s^2": 1.0, "m/s2": 1.0, "m/s/s": 1.0, "m/s**2": 1.0, "mps2": 1.0,
    "gal": 0.01, "cm/s^2": 0.01, "cm/s2": 0.01, "cm/s/s": 0.01, "cm/s**2": 0.01, "cm/sec/sec": 0.01,
    "cm/sec2": 0.01, "cm/sec^2": 0.01,
    "mm/s^2": 0.001, "mm/s2": 0.001, "mm/s/s": 0.001, "nm/s^2": 1e-9, "nm/s2": 1e-9, "nm/s/s": 1e-9,
    "g": G, "g0": G,
}


def unit_factor(units: str) -> float:
    """Factor converting a declared acceleration unit (gal, g, m/s^2, cm/s^2, mm/s^2) to m/s^2."""
    key = str(units).strip().lower().replace(" ", "")
    if key.startswith("(") and key.endswith(")"):
        key = key[1:-1]
    if key not in UNIT_FACTORS:
        raise ValueError(f"unknown acceleration unit {units!r} (known: gal, g, m/s^2, cm/s^2, mm/s^2)")
    return UNIT_FACTORS[key]


@dataclass
class Record:
    """One acceleration component: ``acc`` (m/s^2) at step ``dt`` (s) and where it came from."""

    acc: np.ndarray
    dt: float
    event: str = "unknown"
    station: str = "unknown"
    component: str = "unknown"
    units_in_file: str = "m/s^2"
    source: str = "unknown"
    scale_factor: float = 1.0
    start_time: float = 0.0
    history: list[str] = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        self.acc = np.asarray(self.acc, dtype=float)
        self.dt = float(self.dt)
        if self.acc.ndim != 1 or len(self.acc) < 2:
            raise ValueError(f"{self.source}: a record needs a 1-D array of at least 2 samples")
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"{self.source}: the time step must be positive, got {self.dt!r}")
        if not np.all(np.isfinite(self.acc)):
            raise ValueError(f"{self.source}: the record has non-finite samples")

    # --- derived quantities -------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of samples."""
        return len(self.acc)

    @property
    def time(self) -> np.ndarray:
        """Sample times (s): start_time + k dt."""
        return self.start_time + np.arange(self.n) * self.dt

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, (n - 1) dt (s)."""
        return (self.n - 1) * self.dt

    @property
    def pga(self) -> float:
        """Peak ground acceleration max|acc| (m/s^2)."""
        return float(np.abs(self.acc).max())

    @property
    def pga_g(self) -> float:
        """Peak ground acceleration in g (standard gravity, ``drystone.units.G_STANDARD``)."""
        return self.pga / G

    # --- derived records -----------------------------------------------------------------
    def replaced(self, note: str, **changes) -> "Record":
        """Copy with fields changed and ``note`` appended to the history."""
        changes.setdefault("history", list(self.history) + [note])
        changes.setdefault("info", dict(self.info))
        return dataclasses.replace(self, **changes)

    def interpolant(self) -> Callable[[float | np.ndarray], np.ndarray]:
        """a(t) in m/s^2 for t (s) counted from the first sample: linear interpolation
        between samples, zero before the first and after the last."""
        t = np.arange(self.n) * self.dt
        acc = self.acc.copy()

        def a(tq):
            return np.interp(tq, t, acc, left=0.0, right=0.0)

        return a

    def metadata(self) -> dict:
        """JSON-ready description (no samples) for the provenance of a simulation."""
        return {
            "event": self.event, "station": self.station, "component": self.component,
            "source": self.source, "units_in_file": self.units_in_file,
            "scale_factor": self.scale_factor, "dt_s": self.dt, "n_samples": self.n,
            "start_time_s": self.start_time, "duration_s": self.duration,
            "pga_m_s2": self.pga, "pga_g": self.pga_g,
            "history": list(self.history), "info": _jsonable(self.info),
        }

    def __repr__(self) -> str:
        return (f"Record({self.event!r}, {self.station!r}, {self.component!r}, n={self.n}, dt={self.dt:g} s, "
                f"pga={self.pga_g:.3f} g, source={self.source!r})")


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    return x
