"""Numbers that describe a record: PGA, step, duration, predominant frequencies and band,
significant duration, arrival picks. Used by the catalogue and ``python -m drystone.motions spectrum``.

Spectral settings (``SETTINGS``): Fourier amplitude spectrum of the linearly detrended
acceleration with a 5 % cosine (Tukey) taper at each end (``motions.spectra``),
Konno-Ohmachi smoothing (b = 40) evaluated on a logarithmic grid of 100 points per decade
from 0.1 Hz to min(25 Hz, 0.8 x Nyquist); on that smoothed spectrum the predominant
frequencies follow the peak rule of ``motions.spectra`` (height >= 0.5 and prominence
>= 0.1 of the maximum) and the predominant band is the half-amplitude band (level 0.5).

Time measures: Arias-type cumulative energy I(t) = integral of a^2 (normalised to 1);
``t5_s``/``t95_s`` where I reaches 5 %/95 %, significant duration D5-95 = t95 - t5;
``onset_s``: change point of the Akaike information criterion (obspy ``aic_simple``)
between the first sample and the time of the PGA, the usual automatic P pick; ``t5_s``
serves as the arrival of strong (S-wave) shaking on a horizontal component.
All times are on the record's own time axis (``Record.time``).
"""
from __future__ import annotations

import numpy as np

from drystone.motions.record import Record
from drystone.motions import spectra as sp

SETTINGS = {"window": "tukey", "detrend": "linear", "fmin_hz": 0.1, "fmax_hz": 25.0, "per_decade": 100,
            "konno_ohmachi_b": 40.0, "prominence": 0.1, "height": 0.5, "band_level": 0.5}


def smoothed_spectrum(r: Record) -> dict:
    """Raw and smoothed Fourier amplitude (m/s) of the acceleration, per ``SETTINGS``."""
    f, a = sp.fourier_amplitude(r.acc, r.dt, window=SETTINGS["window"], detrend=SETTINGS["detrend"])
    fmax = min(SETTINGS["fmax_hz"], 0.8 * 0.5 / r.dt)
    fmin = max(SETTINGS["fmin_hz"], f[1])
    if not fmin < fmax:
        raise ValueError(f"{r.source}: {r.n} samples at dt {r.dt:g} s ({r.duration:g} s) resolve no frequency in the "
                         f"spectrum's band ({SETTINGS['fmin_hz']:g}-{SETTINGS['fmax_hz']:g} Hz, below 0.8 x Nyquist "
                         f"{0.5 / r.dt:g} Hz): its first frequency 1/(n dt) is {f[1]:.3g} Hz; a record of at least "
                         f"{1 / fmax:.3g} s is needed at this step")
    grid = sp.log_grid(fmin, fmax, SETTINGS["per_decade"])
    s = sp.smooth(f, a, SETTINGS["konno_ohmachi_b"], grid)
    return {"freq_hz": f, "amplitude": a, "grid_hz": grid, "smoothed": s, "fmin_hz": fmin, "fmax_hz": fmax}


def energy_fraction(spec: dict, lo_hz: float, hi_hz: float) -> float:
    """Share of the squared raw Fourier amplitude between fmin and fmax that lies in [lo, hi] Hz."""
    f, a = spec["freq_hz"], spec["amplitude"]
    m = (f >= spec["fmin_hz"]) & (f <= spec["fmax_hz"])
    tot = float((a[m] ** 2).sum())
    inside = float((a[m & (f >= lo_hz) & (f <= hi_hz)] ** 2).sum())
    return inside / tot if tot > 0 else 0.0


def arias_times(r: Record) -> tuple[float, float]:
    """Times (s) at 5 % and 95 % of the cumulative squared acceleration."""
    e = np.cumsum(r.acc ** 2)
    if e[-1] <= 0:
        return float(r.time[0]), float(r.time[-1])
    e = e / e[-1]
    t = r.time
    return float(np.interp(0.05, e, t)), float(np.interp(0.95, e, t))


def onset_time(r: Record) -> float | None:
    """AIC change point (s) before the PGA, or None when the PGA is in the first 10 samples."""
    from obspy.signal.trigger import aic_simple

    ipk = int(np.argmax(np.abs(r.acc)))
    if ipk < 10:
        return None
    aic = aic_simple(r.acc[: ipk + 1])
    k = int(np.argmin(aic[1:-1])) + 1
    return float(r.time[k])


def describe(r: Record, spec: dict | None = None) -> dict:
    """JSON-ready summary of a record (units in the key names)."""
    spec = spec or smoothed_spectrum(r)
    g, s = spec["grid_hz"], spec["smoothed"]
    peaks = sp.predominant_frequencies(g, s, prominence=SETTINGS["prominence"], height=SETTINGS["height"])
    band = sp.predominant_band(g, s, level=SETTINGS["band_level"])
    t5, t95 = arias_times(r)
    return {
        "pga_g": r.pga_g, "pga_m_s2": r.pga, "t_pga_s": float(r.time[int(np.argmax(np.abs(r.acc)))]),
        "dt_s": r.dt, "n_samples": r.n, "duration_s": r.duration, "start_time_s": r.start_time,
        "predominant_frequencies_hz": [round(x, 3) for x in peaks],
        "predominant_band_hz": [round(band[0], 3), round(band[1], 3)],
        "spectrum_range_hz": [round(spec["fmin_hz"], 4), round(spec["fmax_hz"], 3)],
        "t5_s": t5, "t95_s": t95, "significant_duration_s": t95 - t5, "onset_s": onset_time(r),
    }
