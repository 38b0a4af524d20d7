"""From a case's ``[[stages]]`` excitation table to samples for the simulation.

``for_stage(stage) -> (acc, dt, meta)``, as ``drystone.runner`` calls it: ``acc`` in
m/s^2 at step ``dt`` (s) (the record's own step; the load programme interpolates
linearly between samples, or use ``motions.processing.resample``), and ``meta`` the
record's ``metadata()`` plus ``motion`` and ``record`` (catalogue name or file) for the
provenance of the run. Stage keys used: ``motion`` (sine, white_noise or record),
``record`` (catalogue name, see ``motions.catalogue.names()``, a FEMA P695 id such as
``fema:12a`` or ``fema:nearfield_pulse:3b`` (``motions.fema``, ASSUMED stand-ins), or a file path; a case
file's path is relative to the case file's folder, made absolute by ``drystone.model.case``;
called directly, a relative path is tried in the working directory, then the repository
root),
``frequency_hz``/``amplitude`` (sine), ``seed`` (white noise), ``pga_g`` (scale to this
PGA, exact) and ``duration`` (s; a longer record is trimmed to it, with a note), and
``site`` (a site-profile file, ``motions.site``): the motion, scaled to ``pga_g`` as the
motion AT ROCK (the outcrop motion of the bedrock), is then propagated up the soil column;
the surface motion is what the platform gets (``motion_for_stage`` keeps both). Bad
parameters (a sine too fast for its samples, too many samples) raise ValueError, which
``drystone.runner`` reports as a CaseError naming the case file and stage.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from dataclasses import dataclass

from drystone.motions import catalogue, fema, generators, processing, readers
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
        elif fema.parse_id(name):
            r = fema.load_id(name)
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


@dataclass
class StageMotion:
    """What an excitation stage applies (``applied``, m/s^2) and, with a ``site``, the
    record at rock it came from (``bedrock``) and ``motions.site.propagate``'s info."""

    applied: Record
    bedrock: Record | None = None
    site: dict | None = None


def motion_for_stage(s: dict) -> StageMotion:
    """The stage's record (scaled and trimmed as it says), propagated through its ``site``
    profile if it has one (scaling first: ``pga_g`` is the PGA at rock)."""
    r = record_for_stage(s)
    if not s.get("site"):
        return StageMotion(r)
    from drystone.motions import site

    surface, info = site.propagate(r, site.read_profile(s["site"]))
    return StageMotion(surface, r, info)


def stage_meta(s: dict, m: StageMotion) -> dict:
    """Provenance of a stage's motion: the applied record's ``metadata()``, ``motion``,
    ``record`` and, with a site, ``site`` (profile file, hash, f0, amplification, PGA at rock
    and at the surface, iterations)."""
    meta = dict(m.applied.metadata(), motion=s.get("motion"), record=s.get("record"))
    if m.site is not None:
        i = m.site
        meta["site"] = {"profile": i["profile"]["file"], "sha256": i["profile"]["sha256"],
                        "name": i["profile"]["name"], "assumed": i["profile"]["assumed"],
                        "pga_rock_g": i["pga_rock_g"], "pga_surface_g": i["pga_surface_g"],
                        "f0_linear_hz": i["f0_linear_hz"], "amplification_linear": i["amplification_linear"],
                        "f0_compatible_hz": i["f0_compatible_hz"], "iterations": i["iterations"],
                        "converged": i["converged"], "method": i["method"],
                        "scaling": "pga_g is the PGA at rock (before propagation); the surface PGA is the site's"}
        from drystone.motions.site import convergence_warning

        warn = convergence_warning(i)
        if warn:
            meta["site"]["warning"] = warn
    return meta


def for_stage(s: dict) -> tuple[np.ndarray, float, dict]:
    """(acc m/s^2, dt s, metadata) for ``drystone.runner``."""
    m = motion_for_stage(s)
    return m.applied.acc, m.applied.dt, stage_meta(s, m)
