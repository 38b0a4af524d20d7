"""From a case's ``[[stages]]`` excitation table to samples for the simulation.

``for_stage(stage) -> (acc, dt, meta)``, as ``drystone.runner`` calls it: ``acc`` in
m/s^2 at step ``dt`` (s) (the record's own step; the load programme interpolates
linearly between samples, or use ``motions.processing.resample``), and ``meta`` the
record's ``metadata()`` plus ``motion`` and ``record`` (catalogue name or file) for the
provenance of the run. Stage keys used: ``motion`` (sine, white_noise or record),
``record`` (catalogue name, see ``motions.catalogue.names()``, or a file path; a case
file's path is relative to the case file's folder, made absolute by ``drystone.model.case``;
called directly, a relative path is tried in the working directory, then the repository
root),
``frequency_hz``/``amplitude`` (sine), ``seed`` (white noise), ``pga_g`` (scale to this
PGA, exact) and ``duration`` (s; a longer record is trimmed to it, with a note). Bad
parameters (a sine too fast for its samples, too many samples) raise ValueError, which
``drystone.runner`` reports as a CaseError naming the case file and stage.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from drystone.motions import catalogue, generators, processing, readers
from drystone.motions.record import Record


def record_for_stage(s: dict) -> Record:
    """The Record an excitation stage asks for (scaled and trimmed as it says)."""
    motion = s.get("motion")
    if motion == "sine":
        r = generators.sine(s["frequency_hz"], duration=s.get("duration") or 10.0,
                            amplitude=s.get("amplitude", 0.5), pga_g=s.get("pga_g"))
        return r
    if motion == "white_noise":
        r = generators.white_noise(duration=s.get("duration") or 30.0, seed=int(s.get("seed", 0) or 0))
    elif motion == "record":
        name = s.get("record")
        if not name:
            raise ValueError("motion 'record' needs 'record' (a catalogue name or a file)")
        if name in catalogue.names():
            r = catalogue.get(name)
        else:
            p = Path(name)
            if not p.is_file() and not p.is_absolute() and (catalogue.ROOT / p).is_file():
                p = catalogue.ROOT / p
            if not p.is_file():
                raise FileNotFoundError(f"record {name!r}: neither a catalogue name ({', '.join(catalogue.names())}) "
                                        f"nor an existing file")
            r = readers.read(p)
    else:
        raise ValueError(f"unknown motion {motion!r}: sine, white_noise or record")
    dur = s.get("duration")
    if motion == "record" and dur is not None and dur < r.duration:
        r = processing.trim(r, r.time[0], r.time[0] + dur)
        r.history[-1] += f" (stage duration {dur:g} s)"
    if s.get("pga_g") is not None:
        r = processing.scale_to_pga(r, pga_g=s["pga_g"])
    return r


def for_stage(s: dict) -> tuple[np.ndarray, float, dict]:
    """(acc m/s^2, dt s, metadata) for ``drystone.runner``."""
    r = record_for_stage(s)
    meta = dict(r.metadata(), motion=s.get("motion"), record=s.get("record"))
    return r.acc, r.dt, meta
