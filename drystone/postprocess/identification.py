"""Vibration-based identification from base and response histories (plain Python, no YADE).

Two procedures, side by side, because the Sacsayhuaman paper's numbers come from the first:

* **The paper's procedure** (``paper_spectrum``): the Fourier amplitude of one 4096-point
  window of an *absolute* displacement sampled at 1000 Hz. Its frequencies can only be
  k x 1000 / 4096 Hz = k x 0.244140625 Hz (``grid_indices``): the eight peaks the paper
  lists are the bins k = 2, 4, 6, 19, 39, 42, 55, 61 of such a window, and an absolute
  displacement under a white-noise base motion is dominated by the base's own motion
  (for flat acceleration, its displacement spectrum falls as 1/f^2), so the lowest peaks
  are those of the input, not of the wall.
* **The proper procedure** (``transfer_function``, ``modal_peaks``): the H1 estimate of
  the transfer function base -> response, H1 = S_xy / S_xx (``scipy.signal.csd`` and
  ``welch``, Hann segments with 50 % overlap, averaged), with the ordinary coherence
  gamma^2 = |S_xy|^2 / (S_xx S_yy). Peaks are kept where the coherence is high (the
  response there is linearly explained by the input) and their damping is read from the
  half-power bandwidth: zeta = (f2 - f1) / (2 f_n) where |H|^2 falls to half its peak
  (exact to O(zeta^2) for a lightly damped, well separated mode).

Units: SI (s, Hz, m, m/s^2); transfer functions in output units per input unit.
"""
from __future__ import annotations

import numpy as np
from scipy import signal

from drystone.model.spec import stage_type

#: the paper's FFT: 1000 Hz sampling (§4.2, line 440), 4096 points (inferred from the grid)
PAPER_RATE_HZ = 1000.0
PAPER_NFFT = 4096
#: the paper quotes its peaks to 3 decimals, some rounded, some truncated (9.520 for bin 39,
#: 9.5215 Hz): each is within 1.5 mHz of k x df. A tolerance of 1 % of the bin (2.4 mHz)
#: keeps the nearest bin unambiguous: 8 frequencies drawn at random would all fall that
#: close to a bin with probability 0.02^8 ~ 3e-14
PAPER_QUOTE_TOL_HZ = 0.01 * PAPER_RATE_HZ / PAPER_NFFT


def grid_step(rate_hz: float = PAPER_RATE_HZ, nfft: int = PAPER_NFFT) -> float:
    """Frequency step (Hz) of an ``nfft``-point FFT of samples at ``rate_hz``."""
    return float(rate_hz) / int(nfft)


def grid_indices(freqs_hz, rate_hz: float = PAPER_RATE_HZ, nfft: int = PAPER_NFFT) -> tuple[np.ndarray, np.ndarray]:
    """Nearest FFT bin k of each frequency and the residual f - k df (Hz)."""
    f = np.asarray(freqs_hz, float)
    df = grid_step(rate_hz, nfft)
    k = np.rint(f / df).astype(int)
    return k, f - k * df


def on_grid(freqs_hz, rate_hz: float = PAPER_RATE_HZ, nfft: int = PAPER_NFFT,
            tol_hz: float = PAPER_QUOTE_TOL_HZ) -> np.ndarray:
    """True where a frequency is an FFT bin (within ``tol_hz``: the precision of a quoted value)."""
    return np.abs(grid_indices(freqs_hz, rate_hz, nfft)[1]) <= tol_hz


def resample_uniform(t, x, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation of x(t) (any axis-0 series) onto a uniform grid at ``rate_hz``
    from t[0] to t[-1]: the paper's 1000 Hz series from recorded histories."""
    t = np.asarray(t, float)
    tn = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1) / rate_hz
    x = np.asarray(x, float)
    if x.ndim == 1:
        return tn, np.interp(tn, t, x)
    return tn, np.stack([np.interp(tn, t, x[:, j]) for j in range(x.shape[1])], axis=1)


def paper_spectrum(t, x, rate_hz: float = PAPER_RATE_HZ, nfft: int = PAPER_NFFT, start_s: float | None = None) -> dict:
    """The paper's procedure: x resampled at ``rate_hz``, one window of ``nfft`` samples
    from ``start_s`` (default the first sample), no taper, no detrending; returns the
    frequencies k df (Hz), the Fourier amplitude dt |X_k| (units of x times s) and the
    window."""
    tn, xn = resample_uniform(t, x, rate_hz)
    i0 = 0 if start_s is None else int(np.searchsorted(tn, start_s - 0.5 / rate_hz))
    if i0 + nfft > len(xn):
        raise ValueError(f"a {nfft}-point window from {tn[min(i0, len(tn) - 1)]:.3f} s needs "
                         f"{nfft / rate_hz:.3f} s of signal; only {(len(xn) - i0) / rate_hz:.3f} s left")
    seg = xn[i0:i0 + nfft]
    amp = np.abs(np.fft.rfft(seg)) / rate_hz
    return {"freq_hz": np.fft.rfftfreq(nfft, 1.0 / rate_hz), "amplitude": amp,
            "window_s": [float(tn[i0]), float(tn[i0] + nfft / rate_hz)], "rate_hz": float(rate_hz), "nfft": int(nfft)}


def largest_peaks(f, a, n: int = 8, fmin_hz: float = 0.0, fmax_hz: float = np.inf) -> list[float]:
    """The ``n`` largest local maxima of a (strictly above both neighbours) in
    [fmin_hz, fmax_hz], as frequencies (Hz) in increasing order: what one reads off a
    plotted spectrum."""
    f = np.asarray(f, float)
    a = np.asarray(a, float)
    idx, _ = signal.find_peaks(a)
    idx = idx[(f[idx] >= fmin_hz) & (f[idx] <= fmax_hz)]
    top = idx[np.argsort(-a[idx])[:n]]
    return sorted(float(f[i]) for i in top)


def transfer_function(x, y, fs_hz: float, nperseg: int, noverlap: int | None = None) -> dict:
    """H1 transfer function from input x to output y (same length, sampled at ``fs_hz``):
    H1 = S_xy / S_xx with Hann segments of ``nperseg`` samples, 50 % overlap by default,
    linear detrend per segment; coherence gamma^2 in [0, 1]. Returns freq_hz, H (complex),
    coherence, n_segments, df_hz."""
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError(f"input and output must be 1-D of the same length, got {x.shape} and {y.shape}")
    if nperseg > len(x):
        raise ValueError(f"nperseg = {nperseg} exceeds the {len(x)} samples")
    noverlap = nperseg // 2 if noverlap is None else int(noverlap)
    kw = dict(fs=fs_hz, window="hann", nperseg=nperseg, noverlap=noverlap, detrend="linear")
    f, sxx = signal.welch(x, **kw)
    _, syy = signal.welch(y, **kw)
    _, sxy = signal.csd(x, y, **kw)  # conj(X) Y: H1 = S_xy / S_xx
    ok = sxx > 0
    h = np.where(ok, sxy / np.where(ok, sxx, 1.0), 0.0)
    den = sxx * syy
    coh = np.where(den > 0, np.abs(sxy) ** 2 / np.where(den > 0, den, 1.0), 0.0)
    nseg = 1 + (len(x) - nperseg) // (nperseg - noverlap)
    return {"freq_hz": f, "H": h, "coherence": np.clip(coh, 0.0, 1.0), "n_segments": int(nseg),
            "df_hz": float(fs_hz / nperseg), "nperseg": int(nperseg)}


def _vertex(f, p, i) -> float:
    """Peak frequency (Hz): vertex of the parabola through bins i-1, i, i+1 of p."""
    if i == 0 or i == len(p) - 1:
        return float(f[i])
    y0, y1, y2 = p[i - 1], p[i], p[i + 1]
    den = y0 - 2 * y1 + y2
    d = 0.5 * (y0 - y2) / den if den < 0 else 0.0
    return float(f[i] + np.clip(d, -0.5, 0.5) * (f[i + 1] - f[i]))


def half_power(f, mag, i: int) -> dict | None:
    """Half-power points around the peak at bin i of |H| (``mag``): the frequencies f1 < f2
    where |H|^2 crosses half its peak value (linear interpolation in |H|^2 between bins),
    and zeta = (f2 - f1) / (2 f_n), f_n the parabolic vertex of |H|^2 at the peak.
    None when a crossing is not reached before the end of the spectrum or a higher peak
    (merged modes)."""
    p = np.asarray(mag, float) ** 2
    half = 0.5 * p[i]
    lo = i
    while lo > 0 and p[lo] > half:
        lo -= 1
    hi = i
    while hi < len(p) - 1 and p[hi] > half:
        hi += 1
    if p[lo] > half or p[hi] > half:
        return None
    if p[lo:i].max(initial=0.0) > p[i] or p[i + 1:hi + 1].max(initial=0.0) > p[i]:
        return None  # a higher peak before the half-power level: merged modes
    f1 = f[lo] + (half - p[lo]) / (p[lo + 1] - p[lo]) * (f[lo + 1] - f[lo])
    f2 = f[hi - 1] + (p[hi - 1] - half) / (p[hi - 1] - p[hi]) * (f[hi] - f[hi - 1])
    fn = _vertex(f, p, i)
    return {"f1_hz": float(f1), "f2_hz": float(f2), "damping_ratio": float((f2 - f1) / (2 * fn)),
            "bins_across": int(hi - lo)}


def modal_peaks(tf: dict, coherence_min: float = 0.9, fmin_hz: float = 0.0, fmax_hz: float = np.inf,
                prominence: float = 0.1, max_peaks: int | None = None) -> list[dict]:
    """Peaks of |H| (local maxima of log10 |H| standing ``prominence`` decades above the
    higher of the valleys around them: 0.1 = a factor 1.26; a mode of damping zeta rises
    by about log10(1 / (2 zeta)), a decade at 5 %) where the coherence is at least ``coherence_min``; per peak: frequency_hz
    (parabolic vertex of |H|^2), amplitude |H|, coherence, and the half-power damping
    (None where the half-power points are not both reached: a peak merged with another,
    or narrower than the resolution). Sorted by frequency; ``max_peaks`` keeps the
    largest ones."""
    f = np.asarray(tf["freq_hz"])
    mag = np.abs(tf["H"])
    coh = np.asarray(tf["coherence"])
    band = (f >= fmin_hz) & (f <= fmax_hz)
    if not band.any():
        return []
    logm = np.log10(np.maximum(mag, 1e-300))
    idx, _ = signal.find_peaks(logm, prominence=prominence)
    idx = [i for i in idx if band[i] and coh[i] >= coherence_min]
    out = []
    for i in idx:
        hp = half_power(f, mag, i)
        out.append({"frequency_hz": _vertex(f, mag ** 2, i), "amplitude": float(mag[i]), "coherence": float(coh[i]),
                    "damping_ratio": None if hp is None else hp["damping_ratio"], "half_power": hp,
                    "resolvable": bool(hp is not None and hp["bins_across"] >= 4)})
    if max_peaks is not None:
        out = sorted(out, key=lambda r: -r["amplitude"])[:max_peaks]
    return sorted(out, key=lambda r: r["frequency_hz"])


# --- runs of the project (results/<case>/): base, absolute and relative histories -------------------

def excitation_stage(spec: dict) -> dict:
    """The (single) excitation stage of a run's spec.json."""
    ex = [st for st in spec["stages"] if stage_type(st) == "excitation"]
    if len(ex) != 1:
        raise ValueError(f"{spec['name']}: identification needs exactly one excitation stage, found {len(ex)}")
    return ex[0]


def base_motion(out) -> dict:
    """Base acceleration (m/s^2) and displacement (m) of a run's excitation, on the record's
    own samples (t in s from the run's start). The displacement is the periodic double
    integral of the band-limited record (``motions.generators.white_noise_displacement``),
    exact for the white-noise records, which start and end at rest."""
    import json
    from pathlib import Path

    from drystone.motions.generators import white_noise_displacement
    from drystone.motions.record import Record

    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    st = excitation_stage(spec)
    acc = np.load(out / st["params"]["acc_file"])
    dt = float(st["params"]["dt"])
    d = white_noise_displacement(Record(acc, dt, source=str(out / st["params"]["acc_file"])))
    t = st["start"] + dt * np.arange(len(acc))
    return {"t": t, "acc": acc, "disp": d, "dt": dt, "direction": np.asarray(st["params"]["direction"], float),
            "start": float(st["start"]), "end": float(st["end"])}


def run_histories(out, component: int = 1) -> dict:
    """During the excitation of a run: t (s), base acceleration and displacement along the
    excitation (interpolated on the recorded samples), and per control point its
    displacement relative to the base and its absolute displacement (base + relative),
    along axis ``component`` (1 = y, out of plane), m."""
    from drystone.postprocess import summary as summ

    h = summ.load_histories(out)
    b = base_motion(out)
    win = (h["t"] >= b["start"]) & (h["t"] <= min(b["end"], b["t"][-1]))
    t = h["t"][win]
    rel = h["cp"][win][:, :, component] - h["cp0"][None, :, component]
    along = b["direction"][component]
    base_d = along * np.interp(t, b["t"], b["disp"])
    base_a = along * np.interp(t, b["t"], b["acc"])
    names = [str(n) for n in h["cp_names"]]
    return {"t": t, "base_acc": base_a, "base_disp": base_d, "names": names,
            "relative": {n: rel[:, j] for j, n in enumerate(names)},
            "absolute": {n: base_d + rel[:, j] for j, n in enumerate(names)}}


def wall_assembly(out, time_s: float | None = None):
    """``drystone.mechanics.modal.Assembly`` of a run's blocks at ``time_s`` (default: the end of the
    last gravity stage, the settled state), in the platform frame (a stone of several parts
    as its parts, moved with the stone), with the materials,
    roles and blocked DOFs of its spec.json; gravity along -z with the run's magnitude."""
    import json
    from pathlib import Path

    from drystone.mechanics import modal
    from drystone.postprocess import snapshots

    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    if time_s is None:
        grav = [st for st in spec["stages"] if stage_type(st) == "gravity"]
        if not grav:
            raise ValueError(f"{out}: no gravity stage: give the time of the static configuration")
        time_s = grav[-1]["end"]
    blocks = spec["blocks"]
    geo = {b["id"]: b for b in json.loads((out / "geometry.json").read_text())["blocks"]}
    fr, = snapshots.frames_at(out, [time_s], world=False)
    t = fr.t
    # a stone of several parts (a clump) enters as the list of its parts, each moved rigidly
    verts = {bid: [fr.place(bid, np.asarray(p, float)) for p in g.get("parts", [g.get("vertices")])]
             for bid, g in geo.items()}
    mats = [spec["materials"][b["material"]] for b in blocks]
    g = spec["gravity"]
    gvec = np.array([0.0, 0.0, -float(g)]) if np.isscalar(g) else np.asarray(g, float)
    asm = modal.Assembly([verts[b["id"]] for b in blocks], moving=[b["role"] == "free" for b in blocks],
                         density=[m["density"] for m in mats], kn=[m["kn"] for m in mats],
                         kt=[m["kt"] for m in mats], blocked=[b.get("blocked_dofs") or "" for b in blocks],
                         ids=[b["id"] for b in blocks], gravity=gvec, mu=[m["mu"] for m in mats])
    asm.sample_time_s = float(t)
    return asm
