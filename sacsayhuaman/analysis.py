"""Sacsayhuaman wall section (paper §4-5): numbers from finished runs, plain Python.

* ``identification_peaks``: white-noise identification (§4.2): Fourier spectra of the
  out-of-plane (y) displacement of the control points A-D relative to the base during the
  excitation, and their peaks.
* ``response``: maximum relative out-of-plane displacement of A-D during an excitation
  (the sine sweeps of §4.3).
* ``residuals``: residual displacement of every stone relative to the base at the end of
  a run, measured from its position after gravity (the settlement under its own weight is
  not a residual of the earthquake), and which stones collapsed (Table 3, Figure 24).

Units: m, s, Hz inside; Table 3 in mm as the paper.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from postprocess import spectra
from postprocess import summary as summ

#: identification peaks: local maxima of the Konno-Ohmachi-smoothed spectrum (b = 100, a
#: narrower window than the records' b = 40, to keep close modes apart) with height and
#: prominence >= 5 % of the maximum, in 0.2-20 Hz (the white noise's band; below 0.2 Hz
#: a 30 s record holds fewer than 6 cycles)
PEAKS = {"bandwidth": 100.0, "height": 0.05, "prominence": 0.05, "fmin_hz": 0.2, "fmax_hz": 20.0}
#: a stone has moved when its residual displacement exceeds this (m): 0.1 mm, the
#: smallest residual the paper's Table 3 reports
MOVED_M = 1e-4


def _load(out: Path) -> tuple[dict, dict, dict]:
    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    s = json.loads((out / "summary.json").read_text())
    return spec, s, summ.load_histories(out)


def _excitation_window(spec: dict, h: dict) -> np.ndarray:
    ex = [st for st in spec["stages"] if st["kind"] == "excitation"]
    if not ex:
        raise ValueError(f"{spec['name']}: the run has no excitation stage")
    return (h["t"] >= ex[0]["start"]) & (h["t"] <= ex[-1]["end"])


def control_point_histories(out: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Time (s) and out-of-plane relative displacement (m) of each control point."""
    _, _, h = _load(out)
    rel = h["cp"] - h["cp0"][None]
    return h["t"], {str(n): rel[:, j, 1] for j, n in enumerate(h["cp_names"])}


def identification_peaks(out: Path) -> dict:
    """Spectra and peak frequencies (Hz) of A-D's out-of-plane relative displacement
    during the excitation of a white-noise run."""
    spec, _, h = _load(out)
    win = _excitation_window(spec, h)
    t = h["t"][win]
    dt = float(np.median(np.diff(t)))
    rel = h["cp"][win] - h["cp0"][None]
    res = {"settings": PEAKS, "dt_s": dt, "duration_s": float(t[-1] - t[0]), "control_points": {}}
    grid = spectra.log_grid(PEAKS["fmin_hz"], min(PEAKS["fmax_hz"], 0.4 / dt))
    for j, name in enumerate(h["cp_names"]):
        f, a = spectra.fourier_amplitude(rel[:, j, 1], dt, window="hann", detrend=True)
        sm = spectra.smooth(f, a, PEAKS["bandwidth"], grid)
        peaks = spectra.predominant_frequencies(grid, sm, prominence=PEAKS["prominence"], height=PEAKS["height"])
        res["control_points"][str(name)] = {"peaks_hz": sorted(peaks), "strongest_hz": peaks[0] if peaks else None,
                                            "freq_hz": grid.tolist(), "amplitude_m_s": sm.tolist()}
    return res


def response(out: Path) -> dict[str, float]:
    """Maximum |out-of-plane relative displacement| (m) of each control point during the
    excitation (and the rest after it)."""
    spec, _, h = _load(out)
    ex = [st for st in spec["stages"] if st["kind"] == "excitation"]
    win = h["t"] >= ex[0]["start"]
    rel = h["cp"][win] - h["cp0"][None]
    return {str(n): float(np.abs(rel[:, j, 1]).max()) for j, n in enumerate(h["cp_names"])}


def residuals(out: Path) -> dict:
    """Residual displacement (m) of every free stone relative to the base at the end of the
    run, from its position at the end of the gravity stage; the largest, the stones within
    10 % of it, and the collapsed stones (summary.json's criterion)."""
    spec, s, h = _load(out)
    grav = [st for st in spec["stages"] if st["kind"] == "gravity"]
    i0 = int(np.searchsorted(h["t"], grav[-1]["end"] - 1e-9)) if grav else 0
    d = np.linalg.norm(h["pos"][-1] - h["pos"][min(i0, len(h["t"]) - 1)], axis=1)
    ids = [int(b) for b in h["block_ids"]]
    collapsed = sorted(int(b) for b, r in s["blocks"].items() if r["collapsed"])
    top = float(d.max())
    carriers = sorted(ids[j] for j in np.flatnonzero(d >= 0.9 * top)) if top > 0 else []
    return {"residual_m": {str(b): float(x) for b, x in zip(ids, d)}, "max_residual_m": top,
            "stones": carriers, "moved": sorted(ids[j] for j in np.flatnonzero(d > MOVED_M)),
            "collapsed": collapsed, "all_collapsed": len(collapsed) == len(ids)}


def table3_row(record: str, pga_g: float, res: dict) -> dict:
    """One row of Table 3: record, PGA (g), maximum residual (mm) and its stones, or
    collapse (the collapsed stones, 'all' when every free stone did)."""
    if res["collapsed"]:
        stones = "all" if res["all_collapsed"] else ", ".join(map(str, res["collapsed"]))
        return {"record": record, "pga_g": pga_g, "max_residual_mm": None, "stones": stones, "collapsed": True}
    return {"record": record, "pga_g": pga_g, "max_residual_mm": 1e3 * res["max_residual_m"],
            "stones": ", ".join(map(str, res["stones"])), "collapsed": False}


def write_table3(rows: list[dict], path: Path) -> Path:
    """results/sacsayhuaman/table3.csv: record, pga_g, max_residual_mm, stones, collapsed."""
    import csv

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["record", "pga_g", "max_residual_mm", "stones", "collapsed"])
        for r in sorted(rows, key=lambda r: (r["record"], r["pga_g"])):
            mm = "" if r["max_residual_mm"] is None else f"{r['max_residual_mm']:.2f}"
            w.writerow([r["record"], f"{r['pga_g']:g}", mm, r["stones"], str(r["collapsed"]).lower()])
    return path


def table3_markdown(rows: list[dict], paper: dict, records=("paruro2014", "cusco2023", "ancash1970")) -> str:
    """Table 3 laid out as the paper's (one column pair per record), ours beside theirs."""
    by = {(r["record"], round(r["pga_g"], 6)): r for r in rows}
    pgas = sorted({round(r["pga_g"], 6) for r in rows} | set(paper["pga_g"]))
    head = "| PGA | " + " | ".join(f"{r}: ours (mm, stones) | {r}: paper" for r in records) + " |"
    lines = [head, "|---|" + "---|---|" * len(records)]
    for g in pgas:
        cells = []
        for rec in records:
            r = by.get((rec, g))
            if r is None:
                ours = "not run"
            elif r["collapsed"]:
                ours = f"collapse ({r['stones']})"
            else:
                ours = f"{r['max_residual_mm']:.1f} ({r['stones']})"
            k = paper["pga_g"].index(g) if g in paper["pga_g"] else None
            if k is None:
                theirs = "-"
            else:
                mm = paper[f"{rec}_mm"][k]
                theirs = f"{mm} ({paper[f'{rec}_stones'][k]})" if mm != "collapse" else \
                    f"collapse ({paper[f'{rec}_stones'][k]})"
            cells += [ours, theirs]
        lines.append(f"| {g:g} g | " + " | ".join(cells) + " |")
    return "\n".join(lines)
