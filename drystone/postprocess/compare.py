"""Comparison of finished runs with the papers' numbers (data/papers/*.toml)."""
from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

from drystone import paths


def paper(name: str) -> dict:
    """The machine-readable numbers of a paper (``sacsayhuaman``, ...)."""
    return tomllib.loads((paths.DATA / "papers" / f"{name}.toml").read_text())


def four_block_rows(summaries: dict[str, dict]) -> list[tuple]:
    """(quantity, ours, paper, note) rows for the gravity4 and settlement4 runs."""
    p = paper("sacsayhuaman")["four_blocks"]
    w = p["weight_N"]
    phi = math.radians(p["friction_angle_deg"])
    rows = []
    g = summaries.get("gravity4")
    if g:
        a = p["block_size_m"][0] * p["block_size_m"][1]
        rows.append(("penetration 1-2 (m)", g.get("penetration_1_2_m"), p["penetration_1_2_m"],
                     f"W/(K_n A) = {w / (p['kn_N_m3'] * a):.4g}"))
        rows.append(("run time, gravity case (s)", g["run"]["wall_time_s"], None, "Abaqus time not given for gravity"))
    s = summaries.get("settlement4")
    if s:
        rows.append(("slip time (s)", s.get("slip_time_s"), p["slip_time_s"],
                     "depends on the layout of Fig. 6 (not available): ours slips at 38 deg tilt"))
        rows.append(("F_t at slip (N)", s.get("slip_force_N"), p["slip_force_N"],
                     f"W sin 38 = {w * math.sin(phi):.2f}; the paper uses F_n = W"))
        rows.append(("F_n at slip (N)", s.get("slip_normal_force_N"), w,
                     f"W cos 38 = {w * math.cos(phi):.2f}"))
        ratio = s.get("slip_force_ratio")
        rows.append(("F_t/F_n at slip", ratio, math.tan(phi), "tan 38 deg"))
        rows.append(("block 1 tilt at slip (deg)", s.get("slip_tilt_deg"), p["friction_angle_deg"], "= friction angle"))
        rows.append(("run time, settlement case (s)", s["run"]["wall_time_s"], p["run_time_settlement_s"], "Abaqus: 8 cores"))
    return rows


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def report(folders: list[str]) -> str:
    """Markdown table comparing the runs in ``folders`` with the paper."""
    summaries = {}
    for f in folders:
        p = Path(f) / "summary.json"
        if not p.is_file():
            raise FileNotFoundError(f"{p}: no summary (run the case first)")
        s = json.loads(p.read_text())
        summaries[s["name"]] = s
    lines = ["| quantity | this package | paper | note |", "|---|---|---|---|"]
    for q, ours, theirs, note in four_block_rows(summaries):
        lines.append(f"| {q} | {_fmt(ours)} | {_fmt(theirs)} | {note} |")
    return "\n".join(lines)
