"""Sacsayhuaman wall section (paper §4-5): numbers from finished runs, plain Python.

* ``identification_peaks``: white-noise identification (§4.2): Fourier spectra of the
  out-of-plane (y) displacement of the control points A-D relative to the base during the
  excitation, and their peaks.
* ``response``: maximum relative out-of-plane displacement of A-D during an excitation
  (the sine sweeps of §4.3).
* ``residuals``: residual displacement of every stone relative to the base at the end of
  a run, after the motion has died out (a last rest stage until the kinetic energy is
  below a threshold), measured from its position after gravity: out of plane (y, the
  paper's Table 3 quantity) and in 3D (|u|), and which stones collapsed as the paper
  reads it (``COLLAPSE``) (Table 3, Figure 24).

Units: m, s, Hz inside; Table 3 in mm as the paper.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.motions import spectra
from drystone.postprocess import summary as summ
from drystone.model.spec import stage_type

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
    ex = [st for st in spec["stages"] if stage_type(st) == "excitation"]
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
    ex = [st for st in spec["stages"] if stage_type(st) == "excitation"]
    win = h["t"] >= ex[0]["start"]
    rel = h["cp"][win] - h["cp0"][None]
    return {str(n): float(np.abs(rel[:, j, 1]).max()) for j, n in enumerate(h["cp_names"])}


def residuals(out: Path) -> dict:
    """Residuals of every free stone relative to the base (platform frame) at the end of the
    run, from its position at the end of the gravity stage (the settlement under its own
    weight is not a residual of the earthquake). The paper's Table 3 quantity is the
    out-of-plane (y) displacement of each stone at the end of the analysis, after motion has
    died out (§5.4); it is read at the centroid, and the run's last stage should be a rest
    ``until_kinetic_below(_per_weight)``: ``settled`` says whether the kinetic energy got
    below its threshold (True), did not within the stage's maximum duration (False, the
    residual is then a snapshot of a moving wall), or the run had no such stage (None).

    Returns, lengths in m: ``out_of_plane_m`` (signed u_y per stone), ``max_out_of_plane_m``
    (max |u_y|) and ``stones`` (the stones within 10 % of it, as the paper lists several);
    the 3D measure ``norm_m`` (|u|), ``max_norm_m``, ``norm_stones``; ``moved`` (|u_y| >
    MOVED_M); ``collapsed`` by the paper's reading (``COLLAPSE``), ``all_collapsed``, and
    ``collapsed_summary`` (summary.json's 3D rule, for comparison); ``left_model``: the stones
    that left the model (summary.json's ``motion`` "unbounded", drystone/mechanics/stability.py
    ModelRegion: fallen off the platform or thrown away): collapsed, their residuals None and
    left out of the maxima (0 when no stone is left on the model); ``settled``, ``settle``
    (run_info's record) and ``end_time_s``."""
    spec, s, h = _load(out)
    grav = [st for st in spec["stages"] if stage_type(st) == "gravity"]
    i0 = min(int(np.searchsorted(h["t"], grav[-1]["end"] - 1e-9)), len(h["t"]) - 1) if grav else 0
    u = h["pos"][-1] - h["pos"][i0]
    ids = [int(b) for b in h["block_ids"]]
    verts = {b["id"]: np.asarray(b["vertices"], float) for b in spec["blocks"]}
    depth = np.array([np.ptp(verts[b][:, 1]) for b in ids])
    height = np.array([np.ptp(verts[b][:, 2]) for b in ids])
    uy, nrm = u[:, 1], np.linalg.norm(u, axis=1)
    gone = np.array([s["blocks"].get(str(b), {}).get("motion") == "unbounded" for b in ids], bool)
    fallen = gone | (np.abs(uy) > 0.5 * depth) | (u[:, 2] < -height)
    collapsed = sorted(ids[j] for j in np.flatnonzero(fallen))

    def largest(x):
        x = np.where(gone, 0.0, x)  # a stone that left the model has no residual
        top = float(x.max()) if len(x) else 0.0
        return top, (sorted(ids[j] for j in np.flatnonzero(x >= 0.9 * top)) if top > 0 else [])

    top, stones = largest(np.abs(uy))
    top3, stones3 = largest(nrm)
    settle = s.get("run", {}).get("settle")

    def per_stone(x):
        return {str(b): None if g else float(v) for b, v, g in zip(ids, x, gone)}

    return {"out_of_plane_m": per_stone(uy), "max_out_of_plane_m": top,
            "stones": stones, "norm_m": per_stone(nrm), "max_norm_m": top3,
            "norm_stones": stones3,
            "moved": sorted(ids[j] for j in np.flatnonzero(gone | (np.abs(uy) > MOVED_M))),
            "collapsed": collapsed, "all_collapsed": len(collapsed) == len(ids),
            "collapsed_summary": sorted(int(b) for b, r in s["blocks"].items() if r["collapsed"]),
            "left_model": sorted(ids[j] for j in np.flatnonzero(gone)),
            "settled": None if settle is None else bool(settle["reached"]), "settle": settle,
            "end_time_s": float(h["t"][-1])}


#: how the paper's collapse is read (§4.3 lines 511-512, §5.1 line 546, §5.3, Table 3): the
#: paper gives no threshold; it calls stones collapsed when the final states (Figs. 24, 26,
#: 29, 32) show them fallen out of the wall ("the collapse of blocks 35, 38, 39 and 40",
#: "collapses abruptly due to overturning", "partial" and "complete collapse"), and then
#: writes "collapse" and those stones instead of a residual (Table 3).
COLLAPSE = ("a stone has collapsed when its centroid has moved out of plane by more than half the stone's own "
            "out-of-plane depth (past the edge of the seat it stood on: the overturning limit of a rigid stone "
            "rocking about its toe, and a slide off its seat alike) or it ends lower than it started by more than "
            "its height (fell); 'all' when every free stone did")


def table3_row(record: str, pga_g: float, res: dict) -> dict:
    """One row of Table 3 (``residuals``): record, PGA (g), the maximum out-of-plane residual
    (mm) and its stones, or collapse (the collapsed stones, 'all' when every free stone
    did) as the paper; the 3D measure (max |u|, mm, and its stones) as an extra column;
    ``settled`` (True, False: motion had not died out, None: not run to rest)."""
    row = {"record": record, "pga_g": pga_g, "max_residual_3d_mm": 1e3 * res["max_norm_m"],
           "stones_3d": ", ".join(map(str, res["norm_stones"])), "settled": res.get("settled")}
    if res["collapsed"]:
        stones = "all" if res["all_collapsed"] else ", ".join(map(str, res["collapsed"]))
        return dict(row, max_residual_mm=None, stones=stones, collapsed=True)
    return dict(row, max_residual_mm=1e3 * res["max_out_of_plane_m"], stones=", ".join(map(str, res["stones"])),
                collapsed=False)


TABLE3_COLUMNS = ["record", "pga_g", "max_residual_mm", "stones", "collapsed", "max_residual_3d_mm", "stones_3d",
                  "settled"]


def write_table3(rows: list[dict], path: Path) -> Path:
    """results/sacsayhuaman/table3.csv: record, pga_g, max_residual_mm (out of plane, relative
    to the base, blank when collapsed), stones (the largest ones, or the collapsed ones),
    collapsed, max_residual_3d_mm and stones_3d (|u|), settled (true, false: the motion had
    not died out at the end, blank: not run to rest)."""
    import csv

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)

    def flag(x):
        return "" if x is None else str(bool(x)).lower()

    with atomic.aside(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(TABLE3_COLUMNS)
        for r in sorted(rows, key=lambda r: (r["record"], r["pga_g"])):
            mm = "" if r["max_residual_mm"] is None else f"{r['max_residual_mm']:.2f}"
            w.writerow([r["record"], f"{r['pga_g']:g}", mm, r["stones"], flag(r["collapsed"]),
                        f"{r['max_residual_3d_mm']:.2f}", r["stones_3d"], flag(r.get("settled"))])
    return path


NOT_SETTLED = "‡"  # table mark: the kinetic energy was still above the threshold at the end


def table3_markdown(rows: list[dict], paper: dict, records=("paruro2014", "cusco2023", "ancash1970")) -> str:
    """Table 3 laid out as the paper's (one column group per record): ours out of plane
    (mm, stones; the paper's quantity), ours in 3D (|u|, mm) and the paper's. A mark
    NOT_SETTLED after ours: the motion had not died out at the end of the run (explained
    under the table)."""
    by = {(r["record"], round(r["pga_g"], 6)): r for r in rows}
    pgas = sorted({round(r["pga_g"], 6) for r in rows} | set(paper["pga_g"]))
    head = "| PGA | " + " | ".join(f"{r}: ours, out of plane (mm, stones) | {r}: ours, 3D (mm) | {r}: paper"
                                   for r in records) + " |"
    lines = [head, "|---|" + "---|---|---|" * len(records)]
    unsettled = False
    for g in pgas:
        cells = []
        for rec in records:
            r = by.get((rec, g))
            if r is None:
                ours, ours3 = "not run", "-"
            else:
                ours = f"collapse ({r['stones']})" if r["collapsed"] else f"{r['max_residual_mm']:.1f} ({r['stones']})"
                if r.get("settled") is False:
                    ours += f" {NOT_SETTLED}"
                    unsettled = True
                # a collapsed stone falls off the platform: its |u| is a fall height, not a residual
                ours3 = "-" if r["collapsed"] else f"{r['max_residual_3d_mm']:.1f} ({r['stones_3d']})"
            k = paper["pga_g"].index(g) if g in paper["pga_g"] else None
            if k is None:
                theirs = "-"
            else:
                mm = paper[f"{rec}_mm"][k]
                theirs = f"{mm} ({paper[f'{rec}_stones'][k]})" if mm != "collapse" else \
                    f"collapse ({paper[f'{rec}_stones'][k]})"
            cells += [ours, ours3, theirs]
        lines.append(f"| {g:g} g | " + " | ".join(cells) + " |")
    if unsettled:
        lines += ["", f"{NOT_SETTLED}: the motion had not died out when the run ended (kinetic energy still above "
                      "the rest stage's threshold at its maximum duration): that residual is a snapshot."]
    return "\n".join(lines)


# --- identification done both ways (issue 11, item 3): drystone/postprocess/identification.py -----------------

#: transfer functions of the wall's runs: base acceleration -> out-of-plane displacement of
#: A-D relative to the base, Hann segments of 1024 samples (5.12 s at the 200 Hz output:
#: 0.195 Hz bins, 10 averages over 30 s with 50 % overlap); peaks standing 0.1 decade out
#: of |H| with coherence >= 0.9, in 0.3-20 Hz (below 0.3 Hz a 5.12 s segment holds under
#: 2 cycles; 20 Hz is the white noise's band)
TF = {"nperseg": 1024, "coherence_min": 0.9, "prominence_decades": 0.1, "fmin_hz": 0.3, "fmax_hz": 20.0}
#: the paper's procedure: the 8 largest peaks in 0-20 Hz of one 4096-point FFT at 1000 Hz
#: of A-D's absolute out-of-plane displacement, from the start of the excitation
PAPER_FFT = {"rate_hz": 1000.0, "nfft": 4096, "peaks": 8, "fmax_hz": 20.0}


def excitation_label(out: Path) -> dict:
    """What drove a white-noise run: which quantity is white, its peak displacement (m),
    PGA (g) and rms acceleration (m/s^2), from the run's spec and base motion."""
    from drystone.postprocess import identification as idf

    spec = json.loads((Path(out) / "spec.json").read_text())
    ex = spec["excitations"][0]
    info = ex.get("info") or {}
    spectrum = info.get("spectrum") or ("displacement" if "displacement" in str(ex.get("event", "")) else "acceleration")
    b = idf.base_motion(out)
    return {"run": Path(out).name, "spectrum": spectrum, "peak_displacement_m": float(np.abs(b["disp"]).max()),
            "pga_g": float(ex["pga_g"]), "rms_acceleration_m_s2": float(np.sqrt(np.mean(b["acc"] ** 2))),
            "duration_s": float(b["end"] - b["start"])}


def white_noise_identification(out: Path) -> dict:
    """Both procedures on one white-noise run, per control point: (a) the paper's FFT of
    the absolute (and, for contrast, the relative) out-of-plane displacement with its 8
    largest peaks and their FFT bins k; (b) the H1 transfer function base acceleration ->
    relative displacement, its coherence and the coherent peaks with half-power damping."""
    from drystone.postprocess import identification as idf

    h = idf.run_histories(out)
    t = h["t"]
    fs = 1.0 / float(np.median(np.diff(t)))
    res = {"excitation": excitation_label(out), "tf_settings": TF, "paper_settings": PAPER_FFT, "fs_hz": fs,
           "base_paper_fft": None, "control_points": {}}
    kw = dict(rate_hz=PAPER_FFT["rate_hz"], nfft=PAPER_FFT["nfft"])
    sp_b = idf.paper_spectrum(t, h["base_disp"], **kw)
    res["base_paper_fft"] = {"freq_hz": sp_b["freq_hz"], "amplitude": sp_b["amplitude"],
                             "peaks_hz": idf.largest_peaks(sp_b["freq_hz"], sp_b["amplitude"], PAPER_FFT["peaks"],
                                                           fmax_hz=PAPER_FFT["fmax_hz"])}
    for n in h["names"]:
        cp = {}
        for kind in ("absolute", "relative"):
            sp = idf.paper_spectrum(t, h[kind][n], **kw)
            pk = idf.largest_peaks(sp["freq_hz"], sp["amplitude"], PAPER_FFT["peaks"], fmax_hz=PAPER_FFT["fmax_hz"])
            cp[f"paper_fft_{kind}"] = {"freq_hz": sp["freq_hz"], "amplitude": sp["amplitude"], "peaks_hz": pk,
                                       "bins": idf.grid_indices(pk, **kw)[0].tolist(), "window_s": sp["window_s"]}
        tf = idf.transfer_function(h["base_acc"], h["relative"][n], fs, TF["nperseg"])
        cp["transfer"] = {"freq_hz": tf["freq_hz"], "H": tf["H"], "coherence": tf["coherence"],
                          "n_segments": tf["n_segments"], "df_hz": tf["df_hz"]}
        cp["peaks"] = idf.modal_peaks(tf, coherence_min=TF["coherence_min"], fmin_hz=TF["fmin_hz"],
                                      fmax_hz=TF["fmax_hz"], prominence=TF["prominence_decades"])
        cp["max_relative_m"] = float(np.abs(h["relative"][n]).max())
        res["control_points"][n] = cp
    return res


def modal_analysis(out: Path, n_modes: int = 12) -> dict:
    """Linearised modes of the wall on its joint springs at the settled state of a run (end
    of gravity), by the package's modal analysis (drystone/analyses/modal.py ``analyse``:
    its balance check, its finite-difference step, its interpretation): the lowest
    ``n_modes`` frequencies (Hz), effective mass ratios for a base motion out of plane (y)
    and in plane (x), and what this study adds: the out-of-plane displacement of A-D and of
    every free block's centroid per mode (mass-normalised), the damped modes and the
    transfer function to A."""
    from drystone.postprocess import identification as idf
    from drystone.postprocess import summary as summ

    from drystone.analyses import modal as modal_analysis

    asm = idf.wall_assembly(out)
    an = modal_analysis.analyse(asm, modes=n_modes, where=str(out))
    res = an["_res"]
    h = summ.load_histories(out)
    i = int(np.argmin(np.abs(h["t"] - asm.sample_time_s)))
    cps = {str(n): (int(b["block"]), h["cp"][i, j]) for j, (n, b) in
           enumerate(zip(h["cp_names"], json.loads((Path(out) / "spec.json").read_text())["control_points"]))}
    modes = []
    for m in an["modes"]:
        phi = res["shapes"][:, m["index"]]
        cp_y = {n: float(asm.point_displacement(phi, b, p)[1]) for n, (b, p) in cps.items()}
        blocks_y = {int(asm.ids[b]): float(asm.point_displacement(phi, asm.ids[b], asm.pos0[b])[1])
                    for b in np.flatnonzero(asm.moving)}
        modes.append({"frequency_hz": m["frequency_hz"], "effective_mass_y": m["effective_mass_ratio"]["y"],
                      "effective_mass_x": m["effective_mass_ratio"]["x"], "control_points_y": cp_y,
                      "blocks_y": blocks_y})
    # the same model with the run's contact damping distributed over each patch (as the
    # dynamic law): complex modes and the transfer function base acceleration -> y of A
    spec = json.loads((Path(out) / "spec.json").read_text())
    xi = [spec["materials"][b["material"]]["damping"] for b in spec["blocks"]]
    q_star = res["q_star"]
    K, M = 0.5 * (res["K"] + res["K"].T), res["M"]
    C = asm.damping(xi, at=q_star)
    fd, zd, _ = asm.damped_modes(K, C, M)
    freqs = np.linspace(0.2, 20.0, 397)
    b_a, p_a = cps["A"]
    X = asm.frequency_response(K, C, M, freqs)
    h_a = np.array([abs(asm.point_displacement(x.real, b_a, p_a)[1] + 1j * asm.point_displacement(x.imag, b_a, p_a)[1])
                    for x in X])
    damped = {"damping_input": sorted(set(float(v) for v in xi)), "frequency_hz": fd[:n_modes].tolist(),
              "damping_ratio": zd[:n_modes].tolist(), "transfer_A": {"freq_hz": freqs.tolist(), "abs_H": h_a.tolist()},
              "peak_A_hz": float(freqs[int(np.argmax(h_a))])}
    rc = asm.reference_contacts
    damped["median_overlap_depth_m"] = float(np.median(rc["volume"] / rc["area"]))
    nearby = an["model"]["nearby_equilibrium"]
    return {"modes": modes, "damped": damped, "ndof": asm.ndof, "contacts": res["contacts"],
            "asymmetry": res["asymmetry"], "residual": res["residual"],
            "residual_at_equilibrium": nearby["residual"] if nearby else None,
            "equilibrium_iterations": nearby["iterations"] if nearby else 0,
            "equilibrium_max_translation_m": nearby["max_translation_m"] if nearby else 0.0,
            "sample_time_s": asm.sample_time_s, "zero_modes": len(an["zero_modes"]),
            "cumulative_effective_mass_y": float(sum(m["effective_mass_y"] for m in modes)),
            "negative_modes": int((res["frequency_hz"] < 0).sum())}
