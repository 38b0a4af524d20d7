"""Figures of a finished run (PNG, matplotlib Agg; plain Python, no YADE).

``standard(out)`` draws what the run recorded: named-contact forces against time (with
the first slip marked, the paper's Figure 9), the relative normal displacement of a
penetration contact (Figure 7), control-point displacements, and the vertical reaction
against time and tilt angle (Figure 13) for tilt runs.
"""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from drystone import atomic  # noqa: E402
from drystone.postprocess import summary as summ  # noqa: E402
from drystone.model.spec import stage_type  # noqa: E402


def contact_forces(spec: dict, h: dict, name: str, path: Path, slip: dict | None = None) -> Path:
    c = h["contacts"][name]
    t = h["t"]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(t, c["fn"], label="normal force $F_n$")
    ax.plot(t, np.linalg.norm(c["ft"], axis=1), label="tangential force $|F_t|$")
    if slip and slip.get("slip_time_s") is not None:
        ax.axvline(slip["slip_time_s"], color="k", ls="--", lw=0.8)
        ax.annotate(f"slip at {slip['slip_time_s']:.2f} s\n$F_t$ = {slip['slip_force_N']:.2f} N, "
                    f"$F_n$ = {slip['slip_normal_force_N']:.2f} N", (slip["slip_time_s"], slip["slip_force_N"]),
                    xytext=(10, 10), textcoords="offset points", fontsize=8)
    for st in spec["stages"][1:]:
        ax.axvline(st["start"], color="0.7", lw=0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("force (N)")
    ax.set_title(f"{spec['name']}: contact {name}")
    ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def penetration_history(spec: dict, h: dict, name: str, path: Path) -> Path:
    """Relative normal displacement of the blocks of a named contact over time."""
    series = []
    for i in range(len(h["t"])):
        hi = dict(h)
        for k in ("pos", "quat"):
            hi[k] = h[k][: i + 1]
        hi["contacts"] = {name: {k: v[: i + 1] for k, v in h["contacts"][name].items()}}
        p = summ.penetration(spec, hi, name)
        series.append(next(iter(p.values())) if p else np.nan)
    series = np.array([np.nan if s is None else s for s in series], float)
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(h["t"], 1e3 * series)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("penetration (mm)")
    ax.set_title(f"{spec['name']}: relative normal displacement at contact {name}")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def reaction(spec: dict, h: dict, path: Path, collapse: dict | None) -> Path:
    """Vertical (true, world) reaction of the moving blocks on the platform and fixed
    blocks against time and tilt (the paper's Figure 13)."""
    from drystone.model.loading import LoadProgramme, Stage

    prog = LoadProgramme([Stage(stage_type(s), s["start"], s["end"], s["params"]) for s in spec["stages"]
                          if stage_type(s) != "excitation"], spec["gravity"])
    up = np.array([prog.true_vertical(t) for t in h["t"]])
    rv = -np.einsum("ij,ij->i", h["reaction"], up)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(h["t"], rv)
    a1.set_xlabel("time (s)")
    a2.plot(h["tilt_deg"], rv)
    a2.set_xlabel("platform tilt (deg)")
    for a in (a1, a2):
        a.set_ylabel("vertical reaction of the moving blocks (N)")
        a.grid(alpha=0.3)
    if collapse:
        a1.axvline(collapse["time_s"], color="r", ls="--", lw=0.8)
        a2.axvline(collapse["angle_deg"], color="r", ls="--", lw=0.8)
        a2.set_title(f"collapse at {collapse['angle_deg']:.2f} deg", fontsize=9)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def control_points(h: dict, path: Path) -> Path:
    rel = h["cp"] - h["cp0"][None]
    fig, ax = plt.subplots(figsize=(8, 4))
    for j, name in enumerate(h["cp_names"]):
        ax.plot(h["t"], 1e3 * rel[:, j, 1], label=f"{name} (out of plane, y)")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("displacement relative to the base (mm)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def standard(out: Path, summary: dict | None = None) -> list[Path]:
    """All standard figures of the run in folder ``out`` (its summary.json, or ``summary``
    before that is written); returns their paths."""
    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    s = summary if summary is not None else json.loads((out / "summary.json").read_text())
    h = summ.load_histories(out)
    made = []
    an = spec.get("analysis", {})
    for c in spec["output"]["contacts"]:
        slip = s if an.get("slip") == c["name"] else None
        made.append(contact_forces(spec, h, c["name"], out / f"contact_{c['name']}.png", slip))
    if an.get("penetration"):
        made.append(penetration_history(spec, h, an["penetration"], out / f"penetration_{an['penetration']}.png"))
    if h["cp"].size:
        made.append(control_points(h, out / "control_points.png"))
    if any(stage_type(st) == "tilt" for st in spec["stages"]):
        made.append(reaction(spec, h, out / "reaction.png", s.get("collapse")))
    return made
