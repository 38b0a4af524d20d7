"""What the contact damping does to overturning by short pulses: the least amplitude of a
one-sine acceleration pulse that overturns a slender block on the penalty contact, at the
paper's damping and at the damping that gives Housner's restitution, beside Zhang & Makris's
rigid block. ``python -m drystone.studies.pulse_overturning [--out DIR] [--tolerance G]``
(``make pulse-overturning``); its table and figure go to docs/damping-and-impacts.md by
``make docs``.

The block: b x d x h = 0.2 x 0.2 x 0.8 m (b along the shaking), 2300 kg/m^3, mu 1 (it rocks,
it does not slide), on the fixed platform, K_n = 2e8 N/m^3 (the paper's), K_t = K_n / 2 (as
drystone/analyses/restitution.py). The pulse: Zhang & Makris (2001, J. Eng. Mech. 127(5),
"Rocking response of free-standing blocks under cycloidal pulses")'s type-A pulse, the base
acceleration a_p sin(omega_p t) for one period, omega_p = (2, 3, 4, 6) x p, p = sqrt(3 g /
(4 R)) the block's frequency parameter (R its half-diagonal), after a gravity stage; then
2.5 s of rest. For each omega_p / p and each damping, ``python -m drystone collapse``
(drystone/analyses/collapse.py) brackets the least pulse amplitude (g) that overturns the
block to ``--tolerance``, its hunt started at 0.8 x the rigid block's value (never below g
tan(alpha), where rocking starts) and stepped by ``FACTOR``.

The dampings: ``PAPER_DAMPING`` (0.8, the paper's mu_0) and the one whose first impact gives
Housner's restitution r = 1 - 1.5 sin^2(alpha) at this K_n
(``restitution.damping_for_restitution`` on the curve of ``make free-decay``,
results/free_decay/free_decay.json, or, without it, on the same curve measured here). The
rigid block's amplitude is ``analytic.min_overturning_pulse`` (Zhang & Makris's equation of
motion with Housner's restitution, checked in tests/test_rocking_pulse.py).

Writes into results/pulse_overturning/ (or ``--out``): ``pulse_overturning.json`` (the
brackets, the runs' count, the dampings, the inputs), ``report.md`` (the table) and
``pulse_overturning.png`` (amplitude against omega_p / p: the rigid block's curve and the
brackets, also written to docs/figures/ by a run into the default folder); the collapse
analyses in ``collapse/``. Units: g for amplitudes, SI otherwise.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from drystone import atomic, paths
from drystone.units import GRAVITY as G

B, D, H = 0.2, 0.2, 0.8  # m: b along the shaking, d, h
RHO = 2300.0  # kg/m^3
MU = 1.0
KN = 2e8  # N/m^3, the paper's
#: the pulse's circular frequency over the block's p (Zhang & Makris's omega_p / p)
RATIOS = (2.0, 3.0, 4.0, 6.0)
#: the paper's damping (mu_0 read as a fraction of critical, docs/damping-and-impacts.md)
PAPER_DAMPING = 0.8
#: the hunt's step between amplitudes (collapse --factor) and its start over the rigid value
FACTOR = 1.25
START = 0.8
#: the final bracket's width, g (collapse --tolerance)
TOLERANCE = 0.02
REST_S = 2.5  # s after the pulse
OUT = paths.ROOT / "results" / "pulse_overturning"
#: the figure docs/damping-and-impacts.md shows (drystone/studies/readme_tables.py ``pulse_overturning``)
DOCS_FIGURE = paths.ROOT / "docs" / "figures" / "pulse_overturning.png"


def p_of(b: float = B, h: float = H, g: float = G) -> float:
    """The block's frequency parameter p = sqrt(3 g / (4 R)), R = sqrt(b^2 + h^2) / 2 (rad/s)."""
    return math.sqrt(3.0 * g / (2.0 * math.hypot(b, h)))


def rigid_amplitude(ratio: float, b: float = B, h: float = H, g: float = G) -> float:
    """Zhang & Makris's least overturning amplitude (g) of the rigid block with Housner's
    restitution, for omega_p = ratio x p (``analytic.min_overturning_pulse``)."""
    from drystone.mechanics import analytic

    return analytic.min_overturning_pulse(ratio * p_of(b, h, g), b, h, None, g=g, levels=80, tol_g=1e-3)


def case(ratio: float, damping: float, kn: float = KN) -> dict:
    """The case (a dict for ``runner.to_toml``): the block on the platform, gravity, one
    sine period at omega_p = ratio x p along y, rest."""
    from drystone.analyses import restitution as rs

    f = ratio * p_of() / (2.0 * math.pi)
    geo = {"generator": "boxes_on_platform", "mu": MU, "damping": damping, "density": RHO, "kn": kn,
           "kt": rs.KT_RATIO * kn, "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [D, B, H]}]}
    return {"case": {"name": f"pulse_{ratio:g}p_damping_{damping:.3g}",
                     "description": f"0.2 x 0.2 x 0.8 m block, one-sine pulse at {ratio:g} p, damping {damping:.3g}",
                     "geometry": geo},
            "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.1},
                       {"type": "excitation", "motion": "sine", "frequency_hz": f, "duration": 1.0 / f,
                        "pga_g": 0.3, "direction": "y"},
                       {"type": "rest", "duration": REST_S}],
            "output": {"interval": 0.01}}


def housner_damping(curve_json: Path | None = None, work: Path | None = None, log=print) -> dict:
    """The damping whose first impact gives Housner's restitution at K_N: from the curve of
    ``make free-decay`` (``curve_json``, at its K_n) or, without it, from the same curve
    measured into ``work``. {"damping", "housner", "curve", "source"}."""
    from drystone.analyses import restitution as rs

    rh = rs.housner_restitution()
    if curve_json is not None and curve_json.is_file():
        d = json.loads(curve_json.read_text())
        if float(d.get("curve_kn", -1.0)) == KN:
            return {"damping": rs.damping_for_restitution(rh, d["curve"]), "housner": rh, "curve": d["curve"],
                    "source": str(curve_json)}
    curve = []
    for xi in rs.CURVE_DAMPINGS:
        r = rs.measure(Path(work) / "restitution", KN, xi, n_impacts=1)["r"]
        curve.append([xi, r[0]])
        log(f"restitution curve: damping {xi:g}: r_1 {r[0]:.3f}")
        if r[0] < rh:  # the curve past Housner's value is not needed
            break
    return {"damping": rs.damping_for_restitution(rh, curve), "housner": rh, "curve": curve,
            "source": "measured (drystone/analyses/restitution.py)"}


def run(out: Path = OUT, tolerance: float = TOLERANCE, ratios=RATIOS, log=print) -> dict:
    """Every bracket (module docstring); writes pulse_overturning.json, report.md and the figure."""
    from drystone.analyses import collapse as C
    from drystone.tomlio import to_toml

    t0 = time.time()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    hd = housner_damping(paths.ROOT / "results" / "free_decay" / "free_decay.json", out, log)
    dampings = [PAPER_DAMPING, round(hd["damping"], 4)]
    log(f"damping matching Housner's r = {hd['housner']:.3f}: {hd['damping']:.4f} ({hd['source']})")
    rows, n_runs = [], 0
    for ratio in ratios:
        rigid = rigid_amplitude(ratio)
        row = {"ratio": ratio, "frequency_hz": ratio * p_of() / (2 * math.pi), "rigid_g": rigid, "dampings": {}}
        for xi in dampings:
            c = case(ratio, xi)
            path = out / "cases" / f"{c['case']['name']}.toml"
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic.write_text(path, to_toml(c))
            start = max(math.tan(math.atan2(B, H)), START * rigid)
            res = C.collapse(path, None, tolerance=tolerance, cap=4.0 * rigid, start=round(start, 3), factor=FACTOR,
                             fill=None, out=out / "collapse" / c["case"]["name"], workers=1, log=lambda *a, **k: None)
            (stem, r), = res["records"].items()
            n_runs += len(r["runs"])
            row["dampings"][f"{xi:g}"] = {"bracket_g": r["pga_at_collapse_g"], "status": r["status"],
                                          "runs": len(r["runs"]), "non_monotonic": r["non_monotonic"]}
            log(f"omega_p/p {ratio:g}, damping {xi:g}: {r['pga_at_collapse_g']} g (rigid {rigid:.3f} g; "
                f"{len(r['runs'])} runs, {time.time() - t0:.0f} s)")
        rows.append(row)
    data = {"block_m": [B, D, H], "density": RHO, "mu": MU, "kn": KN, "p_rad_s": p_of(), "alpha_rad": math.atan2(B, H),
            "dampings": dampings, "housner": hd, "tolerance_g": tolerance, "rest_s": REST_S, "rows": rows,
            "runs": n_runs, "wall_s": time.time() - t0,
            "rigid": "drystone/mechanics/analytic.py min_overturning_pulse (Zhang & Makris 2001, Housner's r)"}
    atomic.write_text(out / "pulse_overturning.json", json.dumps(data, indent=1))
    atomic.write_text(out / "report.md", report(data))
    figure(data, out / "pulse_overturning.png")
    if Path(out).resolve() == OUT.resolve():  # the docs' copy (make docs links it), from the default run only
        figure(data, DOCS_FIGURE)
    return data


def _cell(d: dict) -> str:
    b = d["bracket_g"]
    return "standing at the cap" if not b else f"{b[0]:.2f}-{b[1]:.2f}"


def report(data: dict) -> str:
    """report.md: the table of brackets beside the rigid block's amplitude."""
    xi = [f"{x:g}" for x in data["dampings"]]
    hd = data["housner"]
    lines = ["# Overturning by one-sine pulses: the contact damping against Zhang & Makris's rigid block", "",
             f"Block {B} x {D} x {H} m (b x d x h), {RHO:g} kg/m^3, mu {MU:g}, K_n {KN:g} N/m^3 "
             f"(drystone/studies/pulse_overturning.py); p = {data['p_rad_s']:.3f} rad/s. Least amplitude (g) of "
             f"the pulse a_p sin(omega_p t), one period, that overturns it: the bracket of `drystone collapse` "
             f"(tolerance {data['tolerance_g']:g} g), at the paper's damping {xi[0]} and at {xi[1]}, whose first "
             f"impact gives Housner's restitution {hd['housner']:.3f} ({hd['source']}); rigid: Zhang & Makris "
             "(2001)'s block with Housner's restitution (drystone/mechanics/analytic.py).", "",
             "## Least overturning amplitude", "",
             f"| omega_p / p | pulse Hz | rigid block g | damping {xi[0]} g | / rigid | damping {xi[1]} g | / rigid |",
             "|---|---|---|---|---|---|---|"]
    for row in data["rows"]:
        cells = [f"{row['ratio']:g}", f"{row['frequency_hz']:.2f}", f"{row['rigid_g']:.3f}"]
        for x in xi:
            d = row["dampings"][x]
            b = d["bracket_g"]
            cells += [_cell(d), f"{0.5 * (b[0] + b[1]) / row['rigid_g']:.2f}" if b else "-"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", f"{data['runs']} runs, {data['wall_s'] / 60:.0f} min.", ""]
    return "\n".join(lines)


def figure(data: dict, path: Path) -> None:
    """Amplitude against omega_p / p: the rigid block's curve and each damping's brackets."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    grid = np.linspace(min(r["ratio"] for r in data["rows"]), max(r["ratio"] for r in data["rows"]), 11)
    ax.plot(grid, [rigid_amplitude(x) for x in grid], "k-", label="rigid block (Zhang & Makris), Housner's r")
    for k, (x, mk) in enumerate(zip(data["dampings"], ("o", "s"))):
        pts = [(r["ratio"], r["dampings"][f"{x:g}"]["bracket_g"]) for r in data["rows"]]
        pts = [(q, b) for q, b in pts if b]
        if pts:
            q = np.array([p for p, _ in pts]) + (k - 0.5) * 0.06
            lo, hi = np.array([b[0] for _, b in pts]), np.array([b[1] for _, b in pts])
            ax.errorbar(q, 0.5 * (lo + hi), yerr=0.5 * (hi - lo), fmt=mk, capsize=3,
                        label=f"penalty contact, K_n {KN:g}, damping {x:g}")
    ax.set_xlabel("omega_p / p")
    ax.set_ylabel("least overturning amplitude a_p (g)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.studies.pulse_overturning", description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=OUT, help="output folder (results/pulse_overturning)")
    ap.add_argument("--tolerance", type=float, default=TOLERANCE, help=f"bracket width, g ({TOLERANCE})")
    ap.add_argument("--ratios", type=float, nargs="+", default=list(RATIOS), help="omega_p / p values (2 3 4 6)")
    a = ap.parse_args(argv)
    data = run(a.out, a.tolerance, a.ratios)
    print(report(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
