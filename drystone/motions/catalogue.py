"""The papers' records by name, each resolved to the user's own file or a labelled analogue.

``get(name, user_dir=None) -> Record`` for ``name`` in ``names()``:
``kobe1995`` (JMA Kobe NS, Ogawa et al.), ``paruro2014`` (Tambomachay), ``cusco2023``
(Wanchaq), ``ancash1970`` (Parque de la Reserva, Lima).

1. **User file.** In ``user_dir`` (default ``<repo>/data/records/user``) the first that
   exists of ``<name>.toml``, ``<name>.AT2``/``.at2``, ``.csv``, ``.txt``, ``.dat``,
   ``.asc``, ``.mseed``, ``.miniseed``, ``.sac``. A ``<name>.toml`` names the file and how
   to read it: ``file`` (relative to the TOML), and optionally ``format``, ``component``,
   ``units``, ``dt``, ``event``, ``station``. Without a TOML, the component is the
   paper's (``PAPER[name]["component"]``: NS).
2. **Analogue** from the FEMA P695 far-field set otherwise (``ANALOGUES``), chosen by
   ``select_analogues`` with the rule below; the Record's event says "analogue of ...".

Either way the paper's window is applied (Paruro: first 60 s) and written to the history.

Analogue rule (numbers from ``motions.analysis`` with its stated spectral settings;
candidates are the 44 far-field components; a record chosen for one paper record is
excluded for the later ones, in the order kobe1995, paruro2014, cusco2023, ancash1970;
ties go to the smaller record id, then component a):

* ``kobe1995``: Kobe 1995 components only; the one whose PGA is closest (|ln ratio|) to
  the JMA Kobe record's 818 gal = 0.834 g.
* ``paruro2014``: eligible if the record lasts at least 60 s and the first predominant
  frequency of its first 60 s lies in 0.46-1 Hz; score = overlap / union, on a log
  frequency axis, of its half-amplitude band and 0.46-1 Hz (1 = same band).
* ``cusco2023``: eligible if all its predominant frequencies are >= 1.5 Hz; misfit (s) =
  |onset - 3.97| + |t5 - 5.36| + 0.1 x D5-95 (P arrival, S/strong-motion arrival, and
  "short": 10 s of significant duration cost as much as 1 s of arrival misfit);
  smallest misfit wins.
* ``ancash1970``: eligible if its first predominant frequency lies in 1.3-13 Hz; score =
  log-axis overlap / union of its half-amplitude band and 1.3-13 Hz.

If no candidate is eligible the best score over all is taken and the result says so.
``build()`` returns what ``python -m drystone.motions records`` writes to
``results/records/catalogue.json``: per name, the source, station, component, PGA (g),
duration, step, predominant frequencies and band, and the candidate table behind the choice.
"""
from __future__ import annotations

import hashlib
import math
import tomllib
from pathlib import Path

from drystone.kept import Kept
from drystone.motions import analysis, fema, processing, readers
from drystone.motions.record import G, Record

from drystone.paths import ROOT  # noqa: E402
USER_DIR = ROOT / "data" / "records" / "user"
USER_EXTENSIONS = (".toml", ".AT2", ".at2", ".csv", ".CSV", ".txt", ".dat", ".asc", ".mseed", ".miniseed",
                   ".sac", ".SAC")
TOML_KEYS = {"file", "format", "component", "units", "dt", "event", "station"}

PAPER = {
    "kobe1995": {
        "event": "1995 Hyogo-ken Nanbu (Kobe) earthquake, 17 Jan 1995", "station": "JMA Kobe (Kobe Marine Observatory)",
        "component": "NS", "used_by": "Ogawa et al.", "pga_g": 8.18 / G,  # 818 gal
        "description": "JMA Kobe record, NS component, PGA 818 gal = 0.834 g", "window_s": None},
    "paruro2014": {
        "event": "Paruro earthquake, 2014", "station": "Tambomachay (Cusco)", "component": "NS",
        "used_by": "Sacsayhuaman paper", "band_hz": [0.46, 1.0], "window_s": [0.0, 60.0],
        "description": "predominant frequencies 0.46-1 Hz; the first 60 s were used"},
    "cusco2023": {
        "event": "Cusco earthquake, 18 Feb 2023", "station": "Wanchaq (Cusco)", "component": "NS",
        "used_by": "Sacsayhuaman paper", "band_hz": [1.5, None], "p_arrival_s": 3.97, "s_arrival_s": 5.36,
        "window_s": None, "description": "predominant frequencies >= 1.5 Hz; short record; P at 3.97 s, S at 5.36 s"},
    "ancash1970": {
        "event": "Ancash earthquake, 31 May 1970", "station": "Parque de la Reserva, Lima", "component": "NS",
        "used_by": "Sacsayhuaman paper", "band_hz": [1.3, 13.0], "window_s": None,
        "description": "predominant frequencies 1.3-13 Hz"},
}
ORDER = ("kobe1995", "paruro2014", "cusco2023", "ancash1970")

#: the analogues ``select_analogues()`` picks (frozen so that ``get`` needs no search; a
#: test checks that the rule still gives these): name -> (set, record id, component)
ANALOGUES = {
    "kobe1995": ("farfield", 7, "a"),
    "paruro2014": ("farfield", 5, "b"),
    "cusco2023": ("farfield", 18, "b"),
    "ancash1970": ("farfield", 14, "a"),
}

CUSCO_DURATION_WEIGHT = 0.1  # s of misfit per s of significant duration


def names() -> list[str]:
    """Paper record names, in catalogue order."""
    return list(ORDER)


def _check_name(name: str):
    if name not in PAPER:
        raise KeyError(f"no record {name!r} in the catalogue (known: {', '.join(ORDER)})")


def user_file(name: str, user_dir=None) -> Path | None:
    """The user's file (or TOML) for ``name``, first in USER_EXTENSIONS order, or None."""
    _check_name(name)
    d = Path(user_dir) if user_dir is not None else USER_DIR
    for ext in USER_EXTENSIONS:
        p = d / f"{name}{ext}"
        if p.is_file():
            return p
    return None


def _read_user(name: str, path: Path) -> Record:
    opts: dict = {}
    if path.suffix == ".toml":
        try:
            spec = tomllib.loads(path.read_text())
        except tomllib.TOMLDecodeError as exc:
            raise readers.RecordFormatError(path, None, f"invalid TOML: {exc}") from None
        unknown = set(spec) - TOML_KEYS
        if unknown:
            raise readers.RecordFormatError(path, None, f"unknown keys {sorted(unknown)} (known: {sorted(TOML_KEYS)})")
        if "file" not in spec:
            raise readers.RecordFormatError(path, None, "missing 'file' (the record file, relative to this TOML)")
        path_read = (path.parent / spec.pop("file")).resolve()
        opts.update(spec)
    else:
        path_read = path
    recs = readers.read_all(path_read, format=opts.get("format"), dt=opts.get("dt"), units=opts.get("units"),
                            event=opts.get("event") or PAPER[name]["event"],
                            station=opts.get("station") or PAPER[name]["station"])
    # a single-component file is that component; otherwise the TOML's or the paper's (NS)
    r = recs[0] if len(recs) == 1 and "component" not in opts else \
        readers.pick_component(recs, opts.get("component", PAPER[name]["component"]), path_read)
    r.history.insert(0, f"catalogue {name!r}: the user's file {path}")
    r.info["catalogue"] = {"name": name, "source_kind": "user file", "file": str(path)}
    return r


def _read_analogue(name: str) -> Record:
    set_name, rid, comp = ANALOGUES[name]
    r = fema.load(rid, comp, set_name)
    p = PAPER[name]
    r.event = f"{r.event} [analogue of {p['event']} at {p['station']}]"
    r.history.insert(0, f"catalogue {name!r}: FEMA P695 {set_name} record {rid}{comp} as analogue of "
                        f"{p['event']} at {p['station']} ({p['description']}); see motions.catalogue")
    r.info["catalogue"] = {"name": name, "source_kind": "analogue", "stands_for": f"{p['event']}, {p['station']}",
                           "fema_set": set_name, "fema_record_id": rid, "fema_component": comp}
    return r


def get(name: str, user_dir=None, analogue: bool = False) -> Record:
    """Record for a paper record name: the user's file if present (unless ``analogue``),
    else the FEMA P695 analogue; the paper's window applied."""
    _check_name(name)
    path = None if analogue else user_file(name, user_dir)
    r = _read_user(name, path) if path is not None else _read_analogue(name)
    w = PAPER[name]["window_s"]
    if w is not None:
        t0 = r.time[0] + w[0]
        r = processing.trim(r, t0, r.time[0] + w[1])
        r.history[-1] += f" (the paper used the first {w[1] - w[0]:g} s)"
    return r


# --- analogue selection -------------------------------------------------------------------------
def log_overlap(band: list[float], target: list[float]) -> float:
    """Overlap / union of two frequency intervals on a log axis (0..1)."""
    lo, hi = max(band[0], target[0]), min(band[1], target[1])
    inter = math.log(hi / lo) if hi > lo else 0.0
    union = math.log(max(band[1], target[1]) / min(band[0], target[0]))
    return inter / union if union > 0 else 0.0


def _candidates(set_name: str) -> list[dict]:
    """Each record of the FEMA set with the numbers the rule scores (``analysis.describe`` of
    each): kept by the set's file's bytes (``_KEPT``), the analogue rule and the catalogue
    describe the 44 records once per process."""
    data = fema.data_file(set_name).read_bytes()
    return _KEPT.get((set_name, hashlib.sha256(data).hexdigest()), lambda: _described(set_name))


_KEPT = Kept(4)


def _described(set_name: str) -> list[dict]:
    out = []
    for c in fema.catalogue(set_name):
        r = fema.load(c["record_id"], c["component"], set_name)
        row = {"record_id": c["record_id"], "component": c["component"], "name": c["name"], "event": c["event"],
               "year": c["year"], "station": c["station"], "pga_g": round(r.pga_g, 4), "duration_s": r.duration,
               "dt_s": r.dt}
        d = analysis.describe(r)
        row.update({k: d[k] for k in ("predominant_frequencies_hz", "predominant_band_hz", "onset_s", "t5_s",
                                      "significant_duration_s")})
        if r.duration >= 60.0:
            w = processing.trim(r, r.time[0], r.time[0] + 60.0)
            d60 = analysis.describe(w)
            row["first60s"] = {k: d60[k] for k in ("predominant_frequencies_hz", "predominant_band_hz")}
        out.append(row)
    return out


def _score(name: str, row: dict) -> tuple[bool, float, dict]:
    """(eligible, score (higher is better), the numbers behind it) of one candidate."""
    p = PAPER[name]
    if name == "kobe1995":
        ok = "kobe" in row["event"].lower()
        s = -abs(math.log(row["pga_g"] / p["pga_g"]))
        return ok, s, {"pga_g": row["pga_g"], "abs_log_pga_ratio": -s}
    if name == "paruro2014":
        if "first60s" not in row:
            return False, -1.0, {"duration_s": row["duration_s"], "reason": "shorter than 60 s"}
        w = row["first60s"]
        f1 = w["predominant_frequencies_hz"][0]
        lo, hi = p["band_hz"]
        s = log_overlap(w["predominant_band_hz"], p["band_hz"])
        return lo <= f1 <= hi, s, {"first_predominant_hz": f1, "band_hz": w["predominant_band_hz"],
                                   "log_band_overlap": round(s, 4)}
    if name == "cusco2023":
        fs = row["predominant_frequencies_hz"]
        ok = min(fs) >= p["band_hz"][0]
        onset = row["onset_s"] if row["onset_s"] is not None else 0.0
        mis = (abs(onset - p["p_arrival_s"]) + abs(row["t5_s"] - p["s_arrival_s"])
               + CUSCO_DURATION_WEIGHT * row["significant_duration_s"])
        return ok, -mis, {"predominant_hz": fs, "onset_s": round(onset, 3), "t5_s": round(row["t5_s"], 3),
                          "significant_duration_s": round(row["significant_duration_s"], 3), "misfit_s": round(mis, 4)}
    if name == "ancash1970":
        f1 = row["predominant_frequencies_hz"][0]
        lo, hi = p["band_hz"]
        s = log_overlap(row["predominant_band_hz"], p["band_hz"])
        return lo <= f1 <= hi, s, {"first_predominant_hz": f1, "band_hz": row["predominant_band_hz"],
                                   "log_band_overlap": round(s, 4)}
    raise KeyError(name)


def select_analogues(set_name: str = "farfield") -> dict:
    """Apply the analogue rule (module docstring) to the FEMA set: per name, the choice
    and the candidate table (eligible, score, numbers), best first."""
    cands = _candidates(set_name)
    used: set[int] = set()
    out = {}
    for name in ORDER:
        rows = []
        for row in cands:
            ok, s, why = _score(name, row)
            rows.append({"record_id": row["record_id"], "component": row["component"], "name": row["name"],
                         "event": row["event"], "station": row["station"], "eligible": bool(ok),
                         "excluded_as_used": row["record_id"] in used, "score": round(s, 6), **why})
        pool = [r for r in rows if r["eligible"] and not r["excluded_as_used"]]
        relaxed = not pool
        if relaxed:
            pool = [r for r in rows if not r["excluded_as_used"]]
        pool.sort(key=lambda r: (-r["score"], r["record_id"], r["component"]))
        best = pool[0]
        used.add(best["record_id"])
        rows.sort(key=lambda r: (not r["eligible"], -r["score"], r["record_id"], r["component"]))
        out[name] = {"choice": [set_name, best["record_id"], best["component"]], "relaxed": relaxed,
                     "candidates": rows}
    return out


def build(user_dir=None, selection: dict | None = None) -> dict:
    """Catalogue table (what ``python -m drystone.motions records`` writes)."""
    selection = selection if selection is not None else select_analogues()
    table = {}
    for name in ORDER:
        r = get(name, user_dir)
        d = analysis.describe(r)
        kind = r.info["catalogue"]["source_kind"]
        entry = {
            "paper": PAPER[name], "source_kind": kind, "source": r.source, "event": r.event, "station": r.station,
            "component": r.component, "units_in_file": r.units_in_file, "pga_g": round(r.pga_g, 4),
            "duration_s": round(r.duration, 4), "dt_s": r.dt,
            "predominant_frequencies_hz": d["predominant_frequencies_hz"],
            "predominant_band_hz": d["predominant_band_hz"], "significant_duration_s": round(d["significant_duration_s"], 3),
            "onset_s": None if d["onset_s"] is None else round(d["onset_s"], 3), "t5_s": round(d["t5_s"], 3),
            "history": r.history,
        }
        sel = selection[name]
        entry["analogue"] = {"frozen": list(ANALOGUES[name]), "rule_gives": sel["choice"],
                             "rule_matches_frozen": list(ANALOGUES[name]) == sel["choice"],
                             "relaxed": sel["relaxed"], "candidates": sel["candidates"]}
        table[name] = entry
    return {"analysis_settings": analysis.SETTINGS, "g_m_s2": G, "user_dir": str(Path(user_dir) if user_dir else USER_DIR),
            "records": table}
