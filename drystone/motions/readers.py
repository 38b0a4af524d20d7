"""Read acceleration records into ``Record`` objects (m/s^2, s), whatever the file format.

``read(path, format=None, component=None, dt=None, units=None)`` returns one component;
``read_all`` returns every component in the file.

Each record format is one ``RecordFormat`` entry of ``REGISTRY`` (its name, its
description, how to recognise a file of it, how to read it; ObsPy's ``_is_fmt`` /
``_read_fmt`` pairs are the model). ``FORMATS`` (the names ``format=`` takes),
``detect_format`` and ``read_all``'s dispatch all come from the registry, and so does the
list of formats at the end of this docstring: adding a format is adding one entry.
``detect_format`` (used when ``format=`` is not given) gives a file to the entry that
claims its extension, else to the first entry, in the registry's order, whose ``sniff``
accepts it (the extension and the first 60 lines; ``plain`` accepts anything).

Units are converted to m/s^2 from what the file declares (an explicit ``units=``
overrides only files that declare nothing, and contradicting a declaration is an error).
Multi-component files default to the first horizontal component in the order NS, EW
(Ogawa et al. used the JMA NS component). A malformed file raises ``RecordFormatError``
naming the file and line; a record is never truncated, padded or resampled here.

Formats (``format=``), in the order they are sniffed:
"""
from __future__ import annotations

import re
import textwrap
import unicodedata
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Callable

import numpy as np

from drystone.motions.record import Record, unit_factor

TEXT_EXT = {".txt", ".dat", ".asc", ".acc", ".csv", ".at2", ""}
#: relative tolerance on the uniformity of a time column and on dt agreements
DT_TOL = 0.01


class RecordFormatError(ValueError):
    """A record file that cannot be read as declared; the message names file and line."""

    def __init__(self, path, line: int | None, msg: str):
        self.path, self.line = str(path), line
        super().__init__(f"{path}:{line}: {msg}" if line else f"{path}: {msg}")


# --- helpers ---------------------------------------------------------------------------
def _lines(path: Path) -> list[str]:
    data = Path(path).read_bytes()
    for enc in ("utf-8", "cp932", "latin-1"):
        try:
            return data.decode(enc).splitlines()
        except UnicodeDecodeError:
            continue
    raise RecordFormatError(path, None, "cannot decode the file as text")  # latin-1 never fails


def _plain_ascii(s: str) -> str:
    return unicodedata.normalize("NFKD", s).encode("ascii", "ignore").decode().upper()


def _floats(tokens, path, lineno) -> list[float]:
    try:
        return [float(t.replace("D", "E").replace("d", "e")) for t in tokens]
    except ValueError:
        raise RecordFormatError(path, lineno, f"not a number in {' '.join(tokens)!r}") from None



def _append_row(rows: list, tok: list, line: str, path, k: int) -> None:
    """Append a data row of numbers, refusing text or a row of a different width."""
    if not _is_numeric_row(tok):
        raise RecordFormatError(path, k, f"expected {len(rows[0]) if rows else 3} numbers, got {line.strip()!r}")
    vals = _floats(tok, path, k)
    if rows and len(vals) != len(rows[0]):
        raise RecordFormatError(path, k, f"expected {len(rows[0])} values, got {len(vals)}")
    rows.append(vals)

def _is_numeric_row(tokens) -> bool:
    if not tokens:
        return False
    try:
        for t in tokens:
            float(t.replace("D", "E"))
        return True
    except ValueError:
        return False


def _split(line: str) -> list[str]:
    return [t for t in re.split(r"[,\s;]+", line.strip()) if t]


def _resolve_units(path, declared: str | None, given: str | None, default: str | None = None) -> str:
    if declared and given and unit_factor(declared) != unit_factor(given):
        raise RecordFormatError(path, None, f"the file declares units {declared!r} but units={given!r} was given")
    units = declared or given or default
    if units is None:
        raise RecordFormatError(path, None, "the file does not declare its units: pass units= (gal, g or m/s^2)")
    try:
        unit_factor(units)
    except ValueError as exc:
        raise RecordFormatError(path, None, str(exc)) from None
    return units


COMPONENT_ALIASES = {
    "NS": "NS", "N-S": "NS", "N": "NS", "NORTH": "NS", "N/S": "NS", "SN": "NS",
    "EW": "EW", "E-W": "EW", "E": "EW", "EAST": "EW", "E/W": "EW", "WE": "EW",
    "UD": "UD", "U-D": "UD", "Z": "UD", "UP": "UD", "V": "UD", "VERT": "UD", "U/D": "UD", "DU": "UD",
}


def normalise_component(label: str) -> str:
    """NS, EW, UD for the usual spellings (N-S, N, E-W, Z, ...); otherwise the label upper-cased."""
    key = _plain_ascii(str(label)).strip()
    return COMPONENT_ALIASES.get(key, key)


def pick_component(records: list[Record], component: str | None, path) -> Record:
    """The requested component (None: NS, else EW, else the first) of ``read_all``'s list."""
    if component is None:
        for want in ("NS", "EW"):
            for r in records:
                if normalise_component(r.component) == want:
                    return r
        return records[0]
    want = normalise_component(component)
    for r in records:
        if normalise_component(r.component) == want or r.component == component:
            return r
    have = ", ".join(r.component for r in records)
    raise RecordFormatError(path, None, f"no component {component!r} (the file has {have})")


# --- PEER NGA .AT2 -------------------------------------------------------------------------
def read_peer(path, units: str | None = None, **_) -> list[Record]:
    """PEER NGA .AT2 (NGA-West1 and NGA-West2 headers)."""
    lines = _lines(path)
    if len(lines) < 5:
        raise RecordFormatError(path, len(lines) or None, "a PEER .AT2 file needs 4 header lines and data")
    desc = lines[1].strip()
    m = re.search(r"UNITS\s+OF\s+([A-Z/0-9^*]+)", lines[2].upper())
    declared = m.group(1) if m else None
    h = lines[3].upper()
    m1 = re.search(r"NPTS\s*=\s*([0-9]+)\s*,?\s*DT\s*=\s*([-+0-9.EeDd]+)", h)
    m2 = re.match(r"\s*([0-9]+)\s+([-+0-9.EeDd]+)\s+NPTS\s*,\s*DT", h)
    m = m1 or m2
    if not m:
        raise RecordFormatError(path, 4, f"expected 'NPTS= n, DT= dt SEC' or 'n dt NPTS, DT', got {lines[3].strip()!r}")
    npts, dt = int(m.group(1)), float(m.group(2).replace("D", "E"))
    vals: list[float] = []
    for k, line in enumerate(lines[4:], start=5):
        tok = line.split()
        if tok:
            vals.extend(_floats(tok, path, k))
    if len(vals) != npts:
        raise RecordFormatError(path, 4, f"the header declares NPTS={npts} but the file has {len(vals)} values")
    units = _resolve_units(path, declared, units)
    parts = [p.strip() for p in desc.split(",")]
    if len(parts) >= 3:
        event, station, comp = ", ".join(parts[:-2]), parts[-2], parts[-1]
    else:
        event, station, comp = desc, "unknown", "unknown"
    return [Record(np.asarray(vals) * unit_factor(units), dt, event=event, station=station, component=comp,
                   units_in_file=units, source=str(path), history=[f"read PEER .AT2 {path}"],
                   info={"format": "peer", "header": desc})]


# --- JMA CSV -------------------------------------------------------------------------------
def read_jma(path, units: str | None = None, dt: float | None = None, **_) -> list[Record]:
    """JMA strong-motion CSV (three components in columns, gal)."""
    lines = _lines(path)
    header: dict[str, str] = {}
    labels = None
    rows: list[list[float]] = []
    start = None
    for k, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        tok = [t.strip() for t in line.split(",") if t.strip()]
        if start is None:
            if "=" in line:
                key, _, val = line.partition("=")
                header[_plain_ascii(key).strip().rstrip(".")] = val.strip()
                continue
            if _is_numeric_row(tok):
                start = k
            else:
                labels = [normalise_component(t) for t in tok]
                continue
        _append_row(rows, tok, line, path, k)
    if not rows:
        raise RecordFormatError(path, None, "no data rows")
    data = np.asarray(rows)
    labels = labels or ["NS", "EW", "UD"][: data.shape[1]]
    if len(labels) != data.shape[1]:
        raise RecordFormatError(path, start, f"{len(labels)} column labels but {data.shape[1]} columns")
    rate = header.get("SAMPLING RATE")
    fdt = None
    if rate:
        m = re.match(r"\s*([0-9.]+)\s*HZ", rate.upper())
        if not m:
            raise RecordFormatError(path, None, f"cannot read SAMPLING RATE {rate!r}")
        fdt = 1.0 / float(m.group(1))
    if fdt and dt and abs(fdt - dt) > DT_TOL * fdt:
        raise RecordFormatError(path, None, f"the file declares dt = {fdt:g} s but dt={dt} was given")
    step = fdt or dt
    if step is None:
        raise RecordFormatError(path, None, "no SAMPLING RATE in the header: pass dt=")
    declared = header.get("UNIT")
    units = _resolve_units(path, declared, units)
    station = header.get("SITE CODE", "unknown")
    info = {"format": "jma", **{k.lower().replace(" ", "_"): v for k, v in header.items()}}
    return [Record(data[:, j] * unit_factor(units), step, event="unknown", station=station, component=lab,
                   units_in_file=units, source=str(path), history=[f"read JMA CSV {path}"], info=info)
            for j, lab in enumerate(labels)]


# --- CISMID / REDACIS ----------------------------------------------------------------------
_CISMID_KEYS = [
    ("npts", r"^(NUMERO|NRO|NUM|N)\.?\s*(DE\s+)?(MUESTRAS|DATOS|PUNTOS)|^NPTS"),
    ("rate", r"FRECUENCIA\s+(DE\s+)?MUESTREO|MUESTRAS\s+POR\s+SEGUNDO|^SPS$"),
    ("dt", r"(INTERVALO|PERIODO|PASO)\s+(DE\s+)?(MUESTREO|TIEMPO)|^DT$|^DELTA"),
    ("units", r"^UNIDAD"),
    ("station_code", r"^CODIGO(\s+DE\s+LA)?(\s+ESTACION)?$"),
    ("station", r"^(NOMBRE(\s+DE\s+LA)?\s+)?ESTACION$"),
    ("date", r"^FECHA(\s+DEL?\s+(SISMO|EVENTO|REGISTRO))?$"),
    ("hour", r"^HORA(\s+DEL?\s+(SISMO|EVENTO|REGISTRO))?"),
    ("event", r"^(EVENTO|SISMO)$"),
]


def _cismid_header(line: str):
    m = re.match(r"\s*([^:=]+?)\s*[:=]\s*(.*)$", line)
    if not m:
        return None
    key, val = _plain_ascii(m.group(1)).strip(), m.group(2).strip()
    for name, pat in _CISMID_KEYS:
        if re.search(pat, key):
            return name, val
    return None


def read_cismid(path, units: str | None = None, dt: float | None = None, **_) -> list[Record]:
    """CISMID/REDACIS text: header, then N-S, E-W, U-D columns (gal unless declared)."""
    lines = _lines(path)
    hdr: dict[str, str] = {}
    labels = None
    start = None
    rows: list[list[float]] = []
    for k, line in enumerate(lines, start=1):
        tok = _split(line)
        if not tok:
            continue
        if start is None:
            if _is_numeric_row(tok) and len(tok) in (3, 4):
                start = k
            else:
                kv = _cismid_header(line)
                if kv and kv[0] not in hdr:
                    hdr[kv[0]] = kv[1]
                up = [normalise_component(t) for t in _split(_plain_ascii(line))]
                if {"NS", "EW", "UD"} <= set(up):
                    labels = [t for t in up if t in ("NS", "EW", "UD", "T", "TIEMPO", "TIME", "T(S)")]
                continue
        _append_row(rows, tok, line, path, k)
    if not rows:
        raise RecordFormatError(path, None, "no data rows (3 or 4 numeric columns) after the header")
    data = np.asarray(rows)
    ncol = data.shape[1]
    assumed = labels is None
    if assumed:
        labels = (["T"] if ncol == 4 else []) + ["NS", "EW", "UD"]
    if len(labels) != ncol:
        raise RecordFormatError(path, start, f"{len(labels)} column labels but {ncol} columns")
    if "npts" in hdr:
        m = re.search(r"[0-9]+", hdr["npts"])
        if m and int(m.group()) != len(data):
            raise RecordFormatError(path, start, f"the header declares {m.group()} samples but the file has {len(data)}")
    fdt = None
    if "dt" in hdr:
        m = re.search(r"[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?", hdr["dt"])
        fdt = float(m.group()) if m else None
    elif "rate" in hdr:
        m = re.search(r"[0-9]*\.?[0-9]+", hdr["rate"])
        fdt = 1.0 / float(m.group()) if m else None
    tcol = [j for j, lab in enumerate(labels) if lab not in ("NS", "EW", "UD")]
    start_time = 0.0
    if tcol:
        t = data[:, tcol[0]]
        tdt = _uniform_step(t, path, start)
        fdt = fdt or tdt
        if abs(tdt - fdt) > DT_TOL * fdt:
            raise RecordFormatError(path, start, f"the time column has step {tdt:g} s, the header {fdt:g} s")
        start_time = float(t[0])
    if fdt and dt and abs(fdt - dt) > DT_TOL * fdt:
        raise RecordFormatError(path, None, f"the file declares dt = {fdt:g} s but dt={dt} was given")
    step = fdt or dt
    if step is None:
        raise RecordFormatError(path, None, "no sampling rate or interval in the header: pass dt=")
    declared = None
    if "units" in hdr:
        u = _plain_ascii(hdr["units"])
        if "GAL" in u or "CM/S" in u:
            declared = "gal"
        elif "M/S" in u:
            declared = "m/s^2"
        elif re.search(r"\bG\b", u):
            declared = "g"
        else:
            raise RecordFormatError(path, None, f"cannot read the units {hdr['units']!r}")
    units = _resolve_units(path, declared, units, default="gal")
    station = hdr.get("station") or hdr.get("station_code") or "unknown"
    event = " ".join(v for v in (hdr.get("event"), hdr.get("date"), hdr.get("hour")) if v) or "unknown"
    hist = [f"read CISMID text {path}"]
    if assumed:
        hist.append("no column labels: columns taken as " + ", ".join(labels))
    if "units" not in hdr and declared is None and units == "gal":
        hist.append("no units in the header: gal assumed (REDACIS convention)")
    info = {"format": "cismid", **hdr}
    return [Record(data[:, j] * unit_factor(units), step, event=event, station=station, component=lab,
                   units_in_file=units, source=str(path), start_time=start_time, history=list(hist), info=info)
            for j, lab in enumerate(labels) if lab in ("NS", "EW", "UD")]


def _uniform_step(t: np.ndarray, path, line) -> float:
    if len(t) < 2:
        raise RecordFormatError(path, line, "fewer than 2 samples")
    step = (t[-1] - t[0]) / (len(t) - 1)
    if not step > 0:
        raise RecordFormatError(path, line, "the time column does not increase")
    dev = np.abs(t - (t[0] + np.arange(len(t)) * step))
    if dev.max() > DT_TOL * step:
        k = int(np.argmax(dev))
        raise RecordFormatError(path, line + k if line else None,
                                f"non-uniform time step (sample {k} is {dev[k]:.3g} s off a uniform grid of "
                                f"{step:g} s); resample it explicitly with motions.processing.resample")
    return float(step)


# --- plain text ------------------------------------------------------------------------------
def read_plain(path, dt: float | None = None, units: str | None = None, **_) -> list[Record]:
    """One column (acceleration, needs dt) or two (time, acceleration); '#' comments."""
    hdr: dict[str, str] = {}
    rows, first, titled = [], None, False
    for k, line in enumerate(_lines(path), start=1):
        s = line.strip()
        if not s:
            continue
        if s[0] in "#%!":
            m = re.match(r"[#%!]\s*([A-Za-z_ ]+?)\s*[:=]\s*(.+)$", s)
            if m:
                hdr[m.group(1).strip().lower()] = m.group(2).strip()
            continue
        tok = _split(s)
        if not _is_numeric_row(tok):
            if not rows and not titled:
                titled = True  # one column-title line before the data is allowed
                continue
            raise RecordFormatError(path, k, f"not a number in {s!r}")
        vals = _floats(tok, path, k)
        if rows and len(vals) != len(rows[0]):
            raise RecordFormatError(path, k, f"expected {len(rows[0])} columns, got {len(vals)}")
        if len(vals) not in (1, 2):
            raise RecordFormatError(path, k, f"a plain record has 1 or 2 columns, got {len(vals)}")
        first = first or k
        rows.append(vals)
    if len(rows) < 2:
        raise RecordFormatError(path, None, "fewer than 2 samples")
    data = np.asarray(rows)
    fdt = float(hdr["dt"].split()[0]) if "dt" in hdr else None
    start_time = 0.0
    if data.shape[1] == 2:
        tdt = _uniform_step(data[:, 0], path, first)
        if fdt and abs(tdt - fdt) > DT_TOL * fdt:
            raise RecordFormatError(path, first, f"the time column has step {tdt:g} s, the header {fdt:g} s")
        fdt = tdt
        start_time = float(data[0, 0])
        acc = data[:, 1]
    else:
        acc = data[:, 0]
    if fdt and dt and abs(fdt - dt) > DT_TOL * fdt:
        raise RecordFormatError(path, None, f"the file has dt = {fdt:g} s but dt={dt} was given")
    step = fdt or dt
    if step is None:
        raise RecordFormatError(path, None, "one column and no '# dt = ...' line: pass dt=")
    units = _resolve_units(path, hdr.get("units"), units)
    return [Record(acc * unit_factor(units), step, event=hdr.get("event", "unknown"),
                   station=hdr.get("station", "unknown"), component=hdr.get("component", "unknown"),
                   units_in_file=units, source=str(path), start_time=start_time,
                   history=[f"read plain text {path}"], info={"format": "plain", **hdr})]


# --- obspy -----------------------------------------------------------------------------------
SAC_IACC = 8  # SAC IDEP value for acceleration in nm/s^2


def read_obspy(path, units: str | None = None, obspy_format: str | None = None, **_) -> list[Record]:
    """Any file obspy.read opens; one Record per trace (no merging of gapped traces)."""
    import obspy

    try:
        st = obspy.read(str(path), format=obspy_format)
    except (TypeError, ValueError, OSError) as exc:
        raise RecordFormatError(path, None, f"obspy cannot read it: {exc}") from None
    ids = [tr.id for tr in st]
    dup = {i for i in ids if ids.count(i) > 1}
    if dup:
        raise RecordFormatError(path, None, f"traces {sorted(dup)} come in several pieces (gaps); merge them first")
    out = []
    for tr in st:
        declared = None
        sac = tr.stats.get("sac")
        if sac is not None and str(sac.get("idep", "")).lower() in (str(SAC_IACC), "iacc"):
            declared = "nm/s^2"
        u = _resolve_obspy_units(path, declared, units)
        comp = tr.stats.channel or tr.stats.get("component", "") or "unknown"
        out.append(Record(tr.data.astype(float) * u[1], tr.stats.delta, event="unknown",
                          station=tr.stats.station or "unknown", component=comp, units_in_file=u[0],
                          source=str(path), history=[f"read {tr.stats._format} {path} trace {tr.id}"],
                          info={"format": "obspy", "obspy_format": tr.stats._format, "trace_id": tr.id,
                                "starttime": str(tr.stats.starttime)}))
    return out


def _resolve_obspy_units(path, declared, given):
    if declared == "nm/s^2":
        if given and abs(unit_factor(given) - 1e-9) > 1e-21:
            raise RecordFormatError(path, None, f"the SAC header declares nm/s^2 but units={given!r} was given")
        return "nm/s^2", 1e-9
    if given is None:
        raise RecordFormatError(path, None, "the file does not declare acceleration units: pass units= "
                                "(gal, g, m/s^2); raw counts need instrument correction first")
    return given, unit_factor(given)


# --- the registry ------------------------------------------------------------------------------
class Probe:
    """What the sniffers look at, read once and only when asked: the extension, whether the
    first 4 kB hold a NUL byte, the first 60 lines (``head``) and their text upper-cased
    without accents (``text``)."""

    def __init__(self, path):
        self.path = Path(path)
        self.ext = self.path.suffix.lower()

    @cached_property
    def binary(self) -> bool:
        try:
            return b"\x00" in self.path.read_bytes()[:4096]
        except OSError as exc:
            raise RecordFormatError(self.path, None, str(exc)) from None

    @cached_property
    def head(self) -> list[str]:
        return _lines(self.path)[:60]

    @cached_property
    def text(self) -> str:
        return _plain_ascii("\n".join(self.head))


@dataclass(frozen=True)
class RecordFormat:
    """One record format: ``name`` (what ``format=`` takes), ``description`` (the module's
    documentation of the format), ``sniff(probe) -> bool`` (whether a file is of it),
    ``read(path, dt=, units=) -> list[Record]`` (every component), and ``extensions`` that
    are this format whatever the content (checked before any sniffing)."""

    name: str
    description: str
    sniff: Callable[[Probe], bool]
    read: Callable[..., list[Record]]
    extensions: tuple[str, ...] = ()


def _sniff_obspy(p: Probe) -> bool:
    return p.ext not in TEXT_EXT or p.binary


def _sniff_jma(p: Probe) -> bool:
    if p.ext == ".csv" and ("SITE CODE" in p.text or "SAMPLING RATE" in p.text):
        return True
    return "SITE CODE" in p.text and "SAMPLING RATE" in p.text


def _sniff_peer(p: Probe) -> bool:
    return len(p.head) > 3 and "NPTS" in p.text and "DT" in p.text and "UNITS OF" in p.text


def _sniff_cismid(p: Probe) -> bool:
    return re.search(r"CISMID|REDACIS|ESTACION|MUESTREO|N-S", p.text) is not None


#: every record format, in the order ``detect_format`` sniffs them (binary files first,
#: then the text formats from the most specific header to ``plain``, which takes the rest)
REGISTRY: tuple[RecordFormat, ...] = (
    RecordFormat(
        "obspy",
        "anything ``obspy.read`` opens (MiniSEED, SAC, GSE2, ...): a file whose extension is not "
        "a text one or whose first 4 kB hold a NUL byte. Units must be given (``units=``) unless a "
        "SAC header declares acceleration (IDEP = IACC, nm/s^2); raw counts need instrument "
        "correction first, which is not done here.",
        _sniff_obspy, read_obspy),
    RecordFormat(
        "jma",
        "Japan Meteorological Agency strong-motion CSV: ``KEY= value`` header lines (``SITE CODE``, "
        "``LAT.``, ``LON.``, ``SAMPLING RATE= 100Hz``, ``UNIT = gal``, ``INITIAL TIME``), a label "
        "line (``NS, EW, UD``), then three comma-separated columns.",
        _sniff_jma, read_jma),
    RecordFormat(
        "peer",
        "PEER NGA ``.AT2``: 4 header lines (title; \"event, date, station, component\"; \"... UNITS "
        "OF G\"; \"NPTS= n, DT= dt SEC\" or the older \"n dt NPTS, DT\"), then values.",
        _sniff_peer, read_peer, extensions=(".at2",)),
    RecordFormat(
        "cismid",
        "Peruvian CISMID/REDACIS text: free header lines of which these are understood (accents "
        "and case ignored; ``:`` or ``=`` separators): ``ESTACION`` / ``NOMBRE DE LA ESTACION`` "
        "(station), ``CODIGO`` (station code), ``FECHA`` / ``HORA`` / ``EVENTO`` / ``SISMO`` "
        "(event), ``NUMERO DE MUESTRAS`` / ``NRO. DE MUESTRAS`` / ``NPTS`` (sample count, "
        "checked), ``FRECUENCIA DE MUESTREO`` (Hz) or ``INTERVALO DE MUESTREO`` / ``DT`` (s), "
        "``UNIDADES`` (gal by default, as REDACIS publishes); then an optional label line (``N-S "
        "E-W U-D`` in any order, optionally led by ``T``/``TIEMPO``) and 3 columns (4 with time). "
        "Without a label line the columns are taken as N-S, E-W, U-D.",
        _sniff_cismid, read_cismid),
    RecordFormat(
        "plain",
        "text with one column (acceleration; needs ``dt``) or two (time, acceleration; the step "
        "must be uniform within 1 % of dt). ``#`` comment lines may declare ``# dt = 0.01``, "
        "``# units = gal``, ``# event = ...``, ``# station = ...``, ``# component = ...``.",
        lambda p: True, read_plain),
)

#: the names ``format=`` takes, in sniffing order
FORMATS = tuple(f.name for f in REGISTRY)

if __doc__:  # the format list of the module's documentation, from the registry
    __doc__ += "".join("\n" + textwrap.fill(f'* ``"{f.name}"`` {f.description}', 90, subsequent_indent="  ")
                       + "\n" for f in REGISTRY)


def record_format(name: str) -> RecordFormat:
    """The registry's entry named ``name``."""
    for f in REGISTRY:
        if f.name == name:
            return f
    raise ValueError(f"unknown record format {name!r} (known: {', '.join(f.name for f in REGISTRY)})")


def detect_format(path) -> str:
    """Guess the format: the entry claiming the extension, else the first whose sniff
    accepts the file (the extension and the first lines)."""
    probe = Probe(path)
    for f in REGISTRY:
        if probe.ext in f.extensions:
            return f.name
    for f in REGISTRY:
        if f.sniff(probe):
            return f.name
    raise RecordFormatError(path, None, "no record format recognises it (known: "
                            f"{', '.join(f.name for f in REGISTRY)})")


def read_all(path, format: str | None = None, dt: float | None = None, units: str | None = None,
             event: str | None = None, station: str | None = None) -> list[Record]:
    """Every component in the file, as Records in m/s^2. ``event``/``station`` fill in what
    the file does not say."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"{p}: no such record file")
    recs = record_format(format or detect_format(p)).read(p, dt=dt, units=units)
    for r in recs:
        if event and r.event == "unknown":
            r.event = event
        if station and r.station == "unknown":
            r.station = station
    return recs


def read(path, format: str | None = None, component: str | None = None, dt: float | None = None,
         units: str | None = None, event: str | None = None, station: str | None = None) -> Record:
    """One component (default: NS, else EW, else the first) of a record file, in m/s^2."""
    return pick_component(read_all(path, format, dt, units, event, station), component, path)
