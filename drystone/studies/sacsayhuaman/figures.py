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

from drystone import atomic  # noqa: E402
from drystone.studies.sacsayhuaman import analysis as an  # noqa: E402


def _frame_wall(ax) -> None:
    """Frame a front elevation of the 8.64 x 4 m section (m), no ticks."""
    ax.set_xlim(-0.5, 9.1)
    ax.set_ylim(-0.5, 4.5)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def _save(fig, path) -> Path:
    """Save as PNG (120 dpi) and close."""
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)


def _finish(fig, ax, path, xlabel: str, ylabel: str, title: str) -> Path:
    """Labels, log grid, legend; save as PNG and close."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return _save(fig, path)


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
    disp = [r for r in sr["runs"] if r.get("start", "rest") == "displacement"]
    rest = [r for r in sr["runs"] if r.get("start", "rest") != "displacement"]
    for k, name in enumerate(("A", "B", "C", "D")):
        colour = f"C{k}"
        for runs, style, what in ((disp, "o-", "Eq. 9 displacement"), (rest, "x:", "from rest")):
            runs = sorted(runs, key=lambda r: r["frequency_hz"])
            if not runs:
                continue
            f = np.array([r["frequency_hz"] for r in runs])
            y = np.array([r["max_relative_m"].get(name, np.nan) for r in runs])
            ax.loglog(f, 1e3 * y, style, color=colour, ms=3, lw=1,
                      label=f"{name}, {what}" if disp and rest else name)
    ax.axvline(paper["identification"]["dominant_frequency_hz"], color="0.5", ls=":", label="paper: 0.976 Hz")
    if sr["dominant_frequency_hz"]:
        ax.axvline(sr["dominant_frequency_hz"], color="r", ls="--", lw=0.8,
                   label=f"ours: {sr['dominant_frequency_hz']:.3f} Hz")
    return _finish(fig, ax, path, "sine frequency (Hz)", "max out-of-plane displacement relative to the base (mm)",
                   "Eq. 9 sines, 0.5 m/s², 10 s, started as the displacement (base velocity jump A/ω) "
                   "(cf. paper Figs. 22-23)")


def _front(v: np.ndarray) -> np.ndarray:
    """Outline (x, z) of a block seen from the front: its vertices' convex hull in x-z."""
    from scipy.spatial import ConvexHull
    p = v[:, [0, 2]]
    return p[ConvexHull(p).vertices]


def final_states(rows: list[dict], key: str, path: Path) -> Path:
    """Front elevation of the wall at the end of each run (one panel per row), stones
    coloured by their out-of-plane residual |u_y| relative to the base (the paper's Table 3
    quantity), collapsed ones (the paper's reading, analysis.COLLAPSE) red; a panel whose
    motion had not died out says so."""
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Polygon

    from drystone.postprocess import snapshots

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
            mm = 1e3 * abs(res["out_of_plane_m"].get(str(bid)) or 0.0)  # None: left the model (collapsed)
            colour = "0.75" if roles[bid] == "fixed" else ("tab:red" if bid in res["collapsed"] else
                                                           cmap(norm(max(mm, 0.1))))
            ax.add_patch(Polygon(_front(v), closed=True, facecolor=colour, edgecolor="k", lw=0.4))
        _frame_wall(ax)
        label = f"{r.get('record', '')} {r[key]:g} g".strip()
        ax.set_title(f"{label}: max |u_y| {1e3 * res['max_out_of_plane_m']:.1f} mm"
                     + (f", {len(res['collapsed'])} collapsed" if res["collapsed"] else "")
                     + (", still moving" if res["settled"] is False else ""), fontsize=8)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=axes.ravel().tolist(), shrink=0.8, label="out-of-plane residual (mm); red: collapsed")
    atomic.savefig(fig, path, dpi=110)
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
    return _save(fig, path)


# --- identification done both ways (issue 11, item 3) -------------------------------------------------

def paper_fft(results: list[dict], paper: dict, path: Path, point: str = "A") -> Path:
    """The paper's procedure on each run: 4096-point FFT (1000 Hz) of the absolute
    out-of-plane displacement of ``point`` and of the base, its 8 largest peaks, the
    paper's 8 peaks and the grid k x 1000/4096 Hz they sit on."""
    n = len(results)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.6 * n + 0.6), squeeze=False, sharex=True)
    df = paper_grid = None
    for ax, r in zip(axes[:, 0], results):
        cp = r["control_points"][point]["paper_fft_absolute"]
        f, a = np.asarray(cp["freq_hz"]), np.asarray(cp["amplitude"])
        df = f[1] - f[0]
        keep = f <= 20.5
        ax.semilogy(f[keep], a[keep], "-", lw=0.9, color="tab:blue", label=f"{point}, absolute")
        b = r["base_paper_fft"]
        ax.semilogy(np.asarray(b["freq_hz"])[keep], np.asarray(b["amplitude"])[keep], "-", lw=0.7, color="0.5",
                    label="base")
        pk = cp["peaks_hz"]
        ax.plot(pk, np.interp(pk, f, a), "v", color="tab:blue", ms=5, label="8 largest peaks")
        for k, p in enumerate(paper["identification"]["white_noise_peaks_hz"]):
            ax.axvline(p, color="tab:red", ls=":", lw=0.9, label="paper's peaks" if k == 0 else None)
        ex = r["excitation"]
        ax.set_title(f"{ex['run']}: white {ex['spectrum']}, peak {1e3 * ex['peak_displacement_m']:.2g} mm, "
                     f"PGA {ex['pga_g']:.2g} g", fontsize=9)
        ax.set_ylabel("|FFT| (m s)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, ncol=4)
        paper_grid = ax
    ax = axes[-1, 0]
    ax.set_xlim(0, 16)
    ax.set_xticks(np.arange(0, 16.1, 2))
    ax.set_xticks(np.arange(0, 16, df), minor=True)
    ax.set_xlabel(f"frequency (Hz); minor ticks: the FFT grid k x 1000/4096 = k x {df:.6f} Hz")
    fig.suptitle("The paper's procedure (one 4.096 s FFT of an absolute displacement): peaks on its grid",
                 fontsize=10)
    return _save(fig, path)


def transfer_functions(results: list[dict], modal: dict | None, path: Path, point: str = "A",
                       min_mass: float = 0.01) -> Path:
    """|H| base acceleration -> displacement of ``point`` relative to the base, and the
    coherence, one line per run; the coherent peaks; the linearised modes with at least
    ``min_mass`` of effective mass out of plane as vertical lines."""
    fig, (ax, axc) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    for r in results:
        cp = r["control_points"][point]
        f, h, c = (np.asarray(cp["transfer"][k]) for k in ("freq_hz", "H", "coherence"))
        ok = f > 0
        ex = r["excitation"]
        line, = ax.loglog(f[ok], np.abs(h[ok]), lw=1,
                          label=f"white {ex['spectrum']}, {1e3 * ex['peak_displacement_m']:.2g} mm, {ex['pga_g']:.2g} g")
        axc.semilogx(f[ok], c[ok], lw=0.9, color=line.get_color())
        for p in cp["peaks"]:
            ax.plot(p["frequency_hz"], p["amplitude"], "o", mfc="none", color=line.get_color(), ms=6)
    if modal:
        first = True
        for m in modal["modes"]:
            if m["frequency_hz"] > 0 and m["effective_mass_y"] >= min_mass:
                for a in (ax, axc):
                    a.axvline(m["frequency_hz"], color="k", ls="--", lw=0.7,
                              label=f"modes, effective mass y >= {min_mass:.0%}" if (first and a is ax) else None)
                first = False
    axc.axhline(results[0]["tf_settings"]["coherence_min"] if results else 0.9, color="tab:red", lw=0.7, ls=":")
    ax.set_ylabel(f"|H| (m per m/s²): {point} relative / base acc.")
    axc.set_ylabel("coherence")
    axc.set_xlabel("frequency (Hz)")
    axc.set_ylim(0, 1.02)
    ax.set_xlim(0.2, 25)
    for a in (ax, axc):
        a.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    ax.set_title("Transfer function base -> control point (H1, Welch averages) and coherence; circles: coherent peaks",
                 fontsize=9)
    return _save(fig, path)


def mode_shapes(modal: dict, run: Path, path: Path, n: int = 6) -> Path:
    """Front elevation of the wall for the ``n`` lowest modes with out-of-plane effective
    mass, blocks coloured by their centroid's out-of-plane modal displacement (normalised
    to the largest)."""
    from matplotlib.patches import Polygon

    blocks = json.loads((Path(run) / "geometry.json").read_text())["blocks"]
    modes = [m for m in modal["modes"] if m["frequency_hz"] > 0]
    modes = sorted(modes, key=lambda m: -m["effective_mass_y"])[:n]
    modes.sort(key=lambda m: m["frequency_hz"])
    cols = min(3, max(1, len(modes)))
    rows = (len(modes) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.0 * rows), squeeze=False)
    cmap = plt.get_cmap("RdBu_r")
    for ax, m in zip(axes.flat, modes):
        y = m["blocks_y"]
        scale = max(abs(v) for v in y.values()) or 1.0
        for b in blocks:
            if b["role"] == "platform":
                continue
            v = np.asarray(b["vertices"])
            val = y.get(b["id"])
            colour = "0.8" if val is None else cmap(0.5 + 0.5 * val / scale)
            ax.add_patch(Polygon(_front(v), closed=True, facecolor=colour, edgecolor="k", lw=0.4))
        _frame_wall(ax)
        ax.set_title(f"{m['frequency_hz']:.2f} Hz: effective mass y {m['effective_mass_y']:.1%}, "
                     f"x {m['effective_mass_x']:.1%}", fontsize=8)
    for ax in list(axes.flat)[len(modes):]:
        ax.axis("off")
    sm = plt.cm.ScalarMappable(norm=plt.Normalize(-1, 1), cmap=cmap)
    fig.colorbar(sm, ax=axes.ravel().tolist(), shrink=0.8, label="out-of-plane modal displacement (normalised)")
    atomic.savefig(fig, path, dpi=110)
    plt.close(fig)
    return Path(path)
