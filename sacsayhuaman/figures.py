"""Figures of the Sacsayhuaman study (PNG, no display): spectra of A-D (paper Fig. 21),
sine-sweep response (Figs. 22-23), final states (Figs. 24, 26, 29, 32) and the relative
displacement of point A against time (Figs. 27, 30, 33, 34)."""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sacsayhuaman import analysis as an  # noqa: E402


def _finish(fig, ax, path, xlabel: str, ylabel: str, title: str) -> Path:
    """Labels, log grid, legend; save as PNG and close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)


def identification(wn: dict, paper: dict, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(9, 4.5))
    for name, cp in wn["control_points"].items():
        line, = ax.loglog(cp["freq_hz"], cp["amplitude_m_s"], lw=1, label=f"{name}: {len(cp['peaks_hz'])} peaks")
        f = np.asarray(cp["freq_hz"])
        a = np.asarray(cp["amplitude_m_s"])
        for pk in cp["peaks_hz"]:
            ax.plot(pk, np.interp(pk, f, a), "v", color=line.get_color(), ms=5)
    for k, pk in enumerate(paper["identification"]["white_noise_peaks_hz"]):
        ax.axvline(pk, color="0.6", ls=":", lw=0.8, label="paper's peaks" if k == 0 else None)
    return _finish(fig, ax, path, "frequency (Hz)", "Fourier amplitude of relative displacement (m s)",
                   "White noise out of plane: spectra of A-D relative to the base (cf. paper Fig. 21)")


def sine_sweep(sr: dict, paper: dict, path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(9, 4.5))
    runs = sr["runs"]
    f = np.array([r["frequency_hz"] for r in runs])
    for name in ("A", "B", "C", "D"):
        y = np.array([r["max_relative_m"].get(name, np.nan) for r in runs])
        ax.loglog(f, 1e3 * y, "o-", ms=3, lw=1, label=name)
    ax.axvline(paper["identification"]["dominant_frequency_hz"], color="0.5", ls=":", label="paper: 0.976 Hz")
    if sr["dominant_frequency_hz"]:
        ax.axvline(sr["dominant_frequency_hz"], color="r", ls="--", lw=0.8,
                   label=f"ours: {sr['dominant_frequency_hz']:.3f} Hz")
    return _finish(fig, ax, path, "sine frequency (Hz)", "max out-of-plane displacement relative to the base (mm)",
                   "Eq. 9 sines, 0.5 m/s², 10 s (cf. paper Figs. 22-23)")


def _front(v: np.ndarray) -> np.ndarray:
    """Outline (x, z) of a block seen from the front: its vertices' convex hull in x-z."""
    from scipy.spatial import ConvexHull
    p = v[:, [0, 2]]
    return p[ConvexHull(p).vertices]


def final_states(rows: list[dict], key: str, path: Path) -> Path:
    """Front elevation of the wall at the end of each run (one panel per row), stones
    coloured by residual displacement, collapsed ones red."""
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Polygon

    from postprocess import snapshots

    n = len(rows)
    cols = min(3, n)
    nr = (n + cols - 1) // cols
    fig, axes = plt.subplots(nr, cols, figsize=(5.2 * cols, 3.0 * nr), squeeze=False)
    norm = LogNorm(1e-1, 1e3)
    cmap = plt.get_cmap("viridis")
    for ax, r in zip(axes.flat, rows):
        out = Path(r["folder"])
        roles = {b["id"]: b["role"] for b in json.loads((out / "geometry.json").read_text())["blocks"]}
        (_, verts, _), = snapshots.positions_at(out, [1e9], world=True)
        res = an.residuals(out)
        for bid, v in verts.items():
            if roles[bid] == "platform":
                continue
            mm = 1e3 * res["residual_m"].get(str(bid), 0.0)
            colour = "0.75" if roles[bid] == "fixed" else ("tab:red" if bid in res["collapsed"] else
                                                           cmap(norm(max(mm, 0.1))))
            ax.add_patch(Polygon(_front(v), closed=True, facecolor=colour, edgecolor="k", lw=0.4))
        ax.set_xlim(-0.5, 9.1)
        ax.set_ylim(-0.5, 4.5)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        label = f"{r.get('record', '')} {r[key]:g} g".strip()
        ax.set_title(f"{label}: max {1e3 * res['max_residual_m']:.1f} mm"
                     + (f", {len(res['collapsed'])} collapsed" if res["collapsed"] else ""), fontsize=8)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=axes.ravel().tolist(), shrink=0.8, label="residual (mm); red: collapsed")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)


def point_a(rows: list[dict], path: Path, title: str) -> Path:
    """Out-of-plane displacement of A relative to the base against time, one line per run."""
    fig, ax = plt.subplots(figsize=(9, 4))
    for r in sorted(rows, key=lambda r: (r.get("record", ""), r["pga_g"])):
        t, cps = an.control_point_histories(Path(r["folder"]))
        label = f"{r['record']} " if "records" in title else ""
        ax.plot(t, 1e3 * cps["A"], lw=0.9, label=f"{label}{r['pga_g']:g} g")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("displacement of A relative to the base (mm)")
    ax.set_title(f"Point A (block 35), {title} (cf. paper Figs. 27, 30, 33, 34)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
