"""PNG of a record and its Fourier spectrum (the layout of the Sacsayhuaman paper's
Figures 25, 28 and 31): acceleration (m/s^2) against time on top, Fourier amplitude
(m/s) against frequency below, raw in grey and Konno-Ohmachi smoothed in black, with the
predominant band shaded and the predominant frequencies marked (settings of
``motions.analysis``). With ``response`` (``motions.intensity.measures(r)["sa"]`` or any
dict with ``periods_s``, ``psa_g`` and ``damping``) the lower row shows the Fourier spectrum
beside the pseudo-acceleration response spectrum Sa(T) (g against period in s).
Matplotlib with the Agg backend (no display needed).
"""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def plot_record(record, path, spec: dict | None = None, summary: dict | None = None, title: str | None = None,
                response: dict | None = None) -> Path:
    """Write the record-plus-spectrum PNG to ``path`` (8 x 6 in, 120 dpi); returns the path."""
    from drystone.motions import analysis

    spec = spec or analysis.smoothed_spectrum(record)
    summary = summary or analysis.describe(record, spec)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if response is None:
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8.0, 6.0), constrained_layout=True)
    else:
        fig, ax = plt.subplot_mosaic([["t", "t"], ["f", "s"]], figsize=(8.0, 6.0), constrained_layout=True)
        ax1, ax2, ax3 = ax["t"], ax["f"], ax["s"]
    ax1.plot(record.time, record.acc, lw=0.6, color="k")
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("acceleration (m/s$^2$)")
    ax1.set_xlim(record.time[0], record.time[-1])
    ax1.grid(alpha=0.3)
    import textwrap
    head = title or (f"{record.event} - {record.station} - {record.component}\n"
                     f"PGA {summary['pga_g']:.3f} g, dt {record.dt:g} s, {record.duration:.2f} s")
    ax1.set_title("\n".join(textwrap.fill(line, 110) for line in head.splitlines()), fontsize=8)
    f, a = spec["freq_hz"], spec["amplitude"]
    m = (f >= spec["fmin_hz"]) & (f <= spec["fmax_hz"])
    ax2.loglog(f[m], a[m], lw=0.4, color="0.6", label="Fourier amplitude")
    ax2.loglog(spec["grid_hz"], spec["smoothed"], lw=1.2, color="k", label="Konno-Ohmachi, b = 40")
    lo, hi = summary["predominant_band_hz"]
    ax2.axvspan(lo, hi, color="tab:orange", alpha=0.2, label=f"predominant band {lo:.2f}-{hi:.2f} Hz")
    for k, fp in enumerate(summary["predominant_frequencies_hz"]):
        ax2.axvline(fp, color="tab:red", lw=0.8, ls="--", label="predominant frequencies" if k == 0 else None)
    ax2.set_xlabel("frequency (Hz)")
    ax2.set_ylabel("Fourier amplitude (m/s)")
    ax2.set_xlim(spec["fmin_hz"], spec["fmax_hz"])
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(fontsize=7, loc="lower left")
    if response is not None:
        per, psa = response["periods_s"], response["psa_g"]
        ax3.plot(per, psa, lw=1.2, color="k")
        ax3.set_xscale("log")
        ax3.set_xlabel("period T (s)")
        ax3.set_ylabel(f"Sa(T), {100 * response['damping']:g} % damped (g)")
        ax3.set_title("pseudo-acceleration response spectrum", fontsize=8)
        ax3.set_xlim(min(per), max(per))
        ax3.set_ylim(bottom=0)
        ax3.grid(alpha=0.3, which="both")
    try:
        fig.savefig(path, dpi=120, format="png")  # as named (callers write aside: drystone/atomic.py)
    finally:
        plt.close(fig)
    return path


def plot_site(rock, surface, info: dict, freqs_hz, tf_linear, tf_compatible, path) -> Path:
    """PNG of a site response (8 x 6 in, 120 dpi): the record at rock and at the surface
    (m/s^2 against s) on top, |transfer function| surface / rock against frequency (Hz, log)
    below, small-strain and strain-compatible, with f0 and the quarter-wave Vs/4H marked."""
    import numpy as np

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8.0, 6.0), constrained_layout=True)
    ax1.plot(surface.time, surface.acc, lw=0.6, color="k", label=f"surface (PGA {surface.pga_g:.3f} g)")
    ax1.plot(rock.time, rock.acc, lw=0.5, color="tab:orange", alpha=0.8, label=f"rock (PGA {rock.pga_g:.3f} g)")
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("acceleration (m/s$^2$)")
    ax1.set_xlim(rock.time[0], rock.time[-1])
    ax1.grid(alpha=0.3)
    ax1.legend(loc="upper right", fontsize=8)
    ax1.set_title(f"{info['profile']['name']}: {rock.event[:60]}", fontsize=9)
    ax2.semilogx(freqs_hz, np.abs(tf_linear), color="k", lw=1.0,
                 label=f"small strain: f0 {info['f0_linear_hz']:.2f} Hz, |H| {info['amplification_linear']:.2f}")
    ax2.semilogx(freqs_hz, np.abs(tf_compatible), color="tab:red", lw=1.0,
                 label=f"strain-compatible: f0 {info['f0_compatible_hz']:.2f} Hz, "
                       f"|H| {info['amplification_compatible']:.2f}")
    ax2.axvline(info["f0_quarter_wave_hz"], color="0.5", ls=":", lw=1.0,
                label=f"Vs/4H = {info['f0_quarter_wave_hz']:.2f} Hz")
    target = info["profile"].get("target") or {}
    if "f0_hz" in target:
        ax2.axvspan(*target["f0_hz"], color="tab:blue", alpha=0.12, label="target f0 range")
    if "amplification" in target:
        ax2.axhline(target["amplification"], color="tab:blue", ls="--", lw=0.8, label="target amplification")
    ax2.set_xlabel("frequency (Hz)")
    ax2.set_ylabel("|surface / rock|")
    ax2.grid(alpha=0.3, which="both")
    ax2.legend(loc="lower left", fontsize=8)
    try:
        fig.savefig(path, dpi=120, format="png")  # as named (callers write aside: drystone/atomic.py)
    finally:
        plt.close(fig)
    return path
