"""Ogawa et al.'s roughness and friction measurements (Tables 1-3): data, averages, figure.

The data live in ``data/ogawa/roughness_friction.csv`` (units: roughness in micrometres,
friction coefficient dimensionless) and the paper's printed averages in
``data/ogawa/paper_values.toml``.
"""
from __future__ import annotations

import csv
import tomllib
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths

DATA = paths.DATA / "ogawa"


def load() -> list[dict]:
    """Rows of the CSV as dicts (numbers as floats, missing as None)."""
    lines = [ln for ln in (DATA / "roughness_friction.csv").read_text().splitlines() if not ln.startswith("#")]
    rows = []
    for r in csv.DictReader(lines):
        rows.append({"table": int(r["table"]), "site": r["site"], "sample": r["sample"] or None,
                     "roughness_um": float(r["roughness_um"]) if r["roughness_um"] else None,
                     "friction": float(r["friction"]) if r["friction"] else None})
    return rows


def paper_values() -> dict:
    return tomllib.loads((DATA / "paper_values.toml").read_text())


def averages() -> dict:
    """Mean roughness (Table 1) and friction (Table 2) per site, recomputed."""
    rows = load()
    out = {"roughness_um": {}, "friction": {}}
    for site in ("Machu Picchu", "Coricancha"):
        out["roughness_um"][site] = float(np.mean([r["roughness_um"] for r in rows if r["table"] == 1 and r["site"] == site]))
        out["friction"][site] = float(np.mean([r["friction"] for r in rows if r["table"] == 2 and r["site"] == site]))
    return out


def check_averages() -> list[tuple]:
    """(quantity, site, recomputed, paper, agrees) with agreement judged at the paper's
    printed precision, one unit of the last digit (0.01 um, 0.01): the paper truncates
    rather than rounds (Machu Picchu roughness: mean 35.3467 um printed 35.34)."""
    mine, paper = averages(), paper_values()["averages"]
    return [(q, site, mine[q][site], paper[q][site], abs(mine[q][site] - paper[q][site]) < 0.01)
            for q in ("roughness_um", "friction") for site in ("Machu Picchu", "Coricancha")]


def figure(path: Path) -> Path:
    """Friction coefficient against roughness per finishing type (Table 3), with the
    in-situ averages (Tables 1-2) marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in load() if r["table"] == 3]
    avg = averages()
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for r in rows:
        ax.plot(r["roughness_um"], r["friction"], "o", color="k")
        ax.annotate(r["site"], (r["roughness_um"], r["friction"]), xytext=(5, 4), textcoords="offset points", fontsize=8)
    for site, mk in (("Machu Picchu", "s"), ("Coricancha", "^")):
        ax.plot(avg["roughness_um"][site], avg["friction"][site], mk, color="tab:red", ms=9,
                label=f"{site} in situ (mean of Tables 1-2)")
    ax.set_xscale("log")
    ax.set_xlabel("roughness (um)")
    ax.set_ylabel("friction coefficient")
    ax.set_title("Ogawa et al. Table 3: friction against roughness per finishing", fontsize=10)
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)
