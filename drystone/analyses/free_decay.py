"""Free-decay check of the contact damping: one block on the platform, pushed and released.

The block (b x d x h = 0.2 x 0.2 x 0.4 m, 2300 kg/m^3, K_n = 2e8, K_t = 1e8 N/m^3, mu 0.7)
settles under gravity while a constant force holds it, then the force is released and it
rings freely about its rest state:

* ``bouncing``: pressed down by 0.5 W; the vertical mode sqrt(K_n A / m);
* ``rocking`` and ``sliding``: pushed sideways at the centroid by 0.06 W (the joint stays
  closed: the rocking lifts the edge by ~40 % of the static penetration, and the shear is
  9 % of mu W); the motion is projected on the two closed-form rocking-sliding modes of the
  block on its joint springs (gravity lowers the rocking stiffness by W h / 2).

Each modal coordinate is read from the recorded velocities (no static offset) and its
damping ratio taken from the logarithmic decrement of successive peaks. ``python -m
drystone free-decay`` runs every mode for both contact geometries and two damping inputs
and writes results/free_decay/report.md and free_decay.json, with the rocking restitution per
impact of a slender block (drystone/analyses/restitution.py) beside them. Units SI.
"""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.mechanics.contact import DETECTIONS
from drystone.postprocess import markdown
from drystone.units import GRAVITY as G  # the runs' gravity (the case default), m/s^2
B, D, H, RHO, KN, KT, MU = 0.2, 0.2, 0.4, 2300.0, 2e8, 1e8, 0.7
MASS = RHO * B * D * H
W = MASS * G
#: (push force as a fraction of W, hold time s, ring time s, sampling interval s)
PUSH = {"bouncing": ((0.0, 0.0, -0.5), 0.3, 0.08, 1e-4), "rocking_sliding": ((0.06, 0.0, 0.0), 0.3, 0.25, 2e-4)}


def log_decrement_ratio(q) -> float:
    """Damping ratio from the successive positive peaks of a decaying oscillation q (a
    velocity: it oscillates about zero), over the first six peaks above 2 % of the first."""
    q = np.asarray(q, float)
    i = np.flatnonzero((q[1:-1] > q[:-2]) & (q[1:-1] >= q[2:]) & (q[1:-1] > 0)) + 1
    pk = q[i]
    pk = pk[pk > 0.02 * pk[0]][:6] if len(pk) else pk
    if len(pk) < 2:
        raise ValueError("fewer than two peaks: no decrement")
    delta = np.log(pk[0] / pk[-1]) / (len(pk) - 1)
    return float(delta / np.sqrt(4 * np.pi ** 2 + delta ** 2))


def rocking_sliding_modes():
    """Closed-form modes of the block on its joint, coordinates (x of the patch centre m,
    rotation about y rad): (M, K, omega rad/s, mode shapes as columns)."""
    from scipy.linalg import eigh

    ic = MASS * (B * B + H * H) / 12
    M = np.array([[MASS, MASS * H / 2], [MASS * H / 2, MASS * H * H / 4 + ic]])
    K = np.diag([KT * B * D, KN * D * B ** 3 / 12 - W * H / 2])
    lam, phi = eigh(K, M)
    return M, K, np.sqrt(lam), phi


def bouncing_omega() -> float:
    return float(np.sqrt(KN * B * D / MASS))


def case(detection: str, xi: float, kind: str) -> dict:
    """The case dictionary of one free-decay run."""
    f, hold, ring, interval = PUSH[kind]
    return {"case": {"name": f"free_decay_{kind}_{detection}_{xi:g}",
                     "geometry": {"generator": "boxes_on_platform", "mu": MU, "damping": xi, "density": RHO,
                                  "kn": KN, "kt": KT,
                                  "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [B, D, H]}]}},
            "contact": {"law": "penalty_coulomb", "detection": detection}, "physics": {"gravity": G},
            "stages": [{"type": "gravity", "duration": hold, "ramp": 0.05}, {"type": "rest", "duration": ring}],
            "forces": [{"block": 1, "force": [c * W for c in f], "start": 0.0, "end": hold}],
            "output": {"interval": interval}}


def ring(outdir: Path, detection: str, xi: float, kind: str) -> dict:
    """Run one free decay (YADE) and return the time (s) and the modal velocities after the
    release: {'t', 'bouncing'} or {'t', 'mode_1', 'mode_2'} (m/s or the modal unit)."""
    from drystone import runner
    from drystone.postprocess import summary as summ

    out = Path(outdir) / kind
    Path(outdir).mkdir(parents=True, exist_ok=True)
    c = case(detection, xi, kind)
    runner.run_dict(c, Path(outdir) / f"{kind}.toml", out_dir=out, quiet=True)
    h = summ.load_histories(out)
    win = h["t"] >= PUSH[kind][1]
    v, w = h["vel"][win, 0], h["angvel"][win, 0]
    res = {"t": h["t"][win], "dt": json.loads((out / "spec.json").read_text())["dt"]}
    if kind == "bouncing":
        res["bouncing"] = v[:, 2]
        return res
    theta = w[:, 1]
    x_p = v[:, 0] - theta * H / 2
    M, _, _, phi = rocking_sliding_modes()
    modal = (phi.T @ M @ np.stack([x_p, theta])).T
    for k in range(2):
        res[f"mode_{k + 1}"] = modal[:, k] * np.sign(modal[0, k])
    return res


def measure(outdir: Path, detection: str, xi: float) -> dict:
    """Damping ratio of the bouncing mode and of the two rocking-sliding modes."""
    r = ring(outdir, detection, xi, "bouncing")
    out = {"bouncing": log_decrement_ratio(r["bouncing"])}
    r = ring(outdir, detection, xi, "rocking_sliding")
    for k in (1, 2):
        out[f"mode_{k}"] = log_decrement_ratio(r[f"mode_{k}"])
    return out


def report(out: Path | None = None, dampings=(0.05, 0.3)) -> Path:
    """Run every mode, both geometries, and write report.md + free_decay.json."""
    import drystone
    from drystone import paths, provenance
    from drystone.analyses import restitution

    out = Path(out) if out is not None else paths.RESULTS / "free_decay"
    out.mkdir(parents=True, exist_ok=True)
    _, _, om, _ = rocking_sliding_modes()
    freqs = {"bouncing": bouncing_omega() / 2 / np.pi, "mode_1": om[0] / 2 / np.pi, "mode_2": om[1] / 2 / np.pi}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for det in DETECTIONS:
            for xi in dampings:
                m = measure(Path(tmp) / f"{det}_{xi:g}", det, xi)
                rows.append({"detection": det, "damping": xi, **m})
                print(f"free decay {det} xi = {xi:g}: " + ", ".join(f"{k} {v:.3f}" for k, v in m.items()), flush=True)
        rest_data, rest_lines = restitution.report_section(Path(tmp))  # the rocking block's impacts
    data = {"frequencies_hz": freqs, "rows": rows, "block_m": [B, D, H], "density": RHO, "kn": KN, "kt": KT,
            "package_version": drystone.__version__, "git": provenance.git_commit(),
            "yade": provenance.yade_version(), "restitution": rest_data}
    atomic.write_text(out / "free_decay.json", json.dumps(data, indent=1))
    lines = ["# Free decay of one block: damping ratio per mode (logarithmic decrement)", "",
             f"Block {B} x {D} x {H} m, {RHO:g} kg/m^3, K_n {KN:g}, K_t {KT:g} N/m^3 on the platform "
             "(drystone/analyses/free_decay.py). Modes: bouncing "
             f"{freqs['bouncing']:.1f} Hz; rocking-sliding {freqs['mode_1']:.1f} Hz (mostly rocking) and "
             f"{freqs['mode_2']:.1f} Hz (mostly sliding), closed form.", "",
             "| geometry | damping asked | bouncing | rocking-sliding 1 | rocking-sliding 2 |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['detection']} | {r['damping']:g} | {r['bouncing']:.3f} | {r['mode_1']:.3f} | "
                     f"{r['mode_2']:.3f} |")
    lines += rest_lines
    return markdown.write(out / "report.md", "\n".join(lines) + "\n")  # and report.html beside it
