"""Rocking restitution: what the contact damping does to the impacts of a rocking block.

A slender rectangular block (base b along x, depth d, height h) stands on the platform
tilted by theta0 < alpha = atan(b / h) about one bottom edge, and is released from rest:
it rocks on its corners, and each change of pivot is an impact. Housner (1963, "The
behavior of inverted pendulum structures during earthquakes", Bull. Seism. Soc. Am. 53(2))
treats the impact as instantaneous, about the new corner, without bounce or
slip: angular momentum about the new corner is conserved, and the angular velocity after
the impact is r times the one before, with, for a rectangular block,

    r = 1 - 1.5 sin^2(alpha)          (restitution of the angular velocity; energy ratio r^2)

(``housner_restitution``; 0.912 for the 0.2 x 0.8 m block here).

How it is measured (``restitution_per_impact``). With a penalty contact the impact lasts a
finite time and the joint passes through a closed phase, so "just before" and "just after"
have no sharp meaning, and the angular velocity is not constant before or after the
impact anyway. Between two impacts the block rocks freely on one corner and keeps its
rocking energy, so the energy ratio across one impact is that of two successive rocking
amplitudes: with theta_n the largest |theta| of half-cycle n (between two zero crossings
of the rotation theta; there the angular velocity is zero and all the rocking energy is
potential),

    r_n = sqrt(E(theta_{n+1}) / E(theta_n)),  E(theta) = m g R [cos(alpha - |theta|) - cos(alpha)]

(``rocking_energy``; R the half-diagonal, E the rigid block's rise of its centroid above
the upright position). This is Housner's ratio exactly for a rigid block (the angular
velocity at theta = 0 before and after the impact carries the whole energy: 1/2 I_O w^2 =
E). The amplitudes are read from the samples by a parabola through the largest sample and
its two neighbours (the third derivative of theta is zero at an extreme, so the error is
the quartic term, ~ p^4 alpha dt^4 / 24). What it leaves out: with a penalty contact the
pivot corner sinks into the platform (delta ~ sqrt(2 theta W / (K_n d)), 2.3 mm at theta =
0.15 rad and K_n 2e8 N/m^3 for this block), so the rigid E(theta) is a little above the
block's own energy (``sunk_rocking_energy`` takes the sink out: 1-6 % on r at K_n 2e8);
and the energy that goes into vibrations of the block on its contact (kept, without
damping) is counted as lost, as it is lost to the rocking.

``measure(folder, kn, damping)`` runs the block in YADE (``block_file``, ``case``) and
returns the restitution of the first impacts; ``damping_for_restitution`` reads the damping
for a target restitution off a measured curve. ``python -m drystone free-decay`` writes the
table and the curve beside the damping ratios (``report_section``). Units SI, angles in
rad.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from drystone.units import GRAVITY as G

#: the block: base b along x (the rocking plane x-z), depth d along y, height h (m); density kg/m^3
B, D, H, RHO = 0.2, 0.2, 0.8, 2300.0
#: K_t as a fraction of K_n, and the friction coefficient (high, so that the block rocks
#: without sliding: the report's 'slide' column, under 1 mm when damped)
KT_RATIO, MU = 0.5, 1.0
#: release angle as a fraction of alpha
THETA0_FRACTION = 0.6
#: impacts are counted while the rocking amplitude after them exceeds this fraction of
#: alpha (0.0049 rad for this block: 5 x the rotation 2 W / (K_n d b^2) = 9e-4 rad at which
#: the joint closes at K_n 2e8 N/m^3)
MIN_AMPLITUDE = 0.02
#: simulated time (s), sampling interval (s) and impacts reported per run
DURATION, INTERVAL, N_IMPACTS = 3.0, 5e-4, 5
#: the report's table (K_n N/m^3 x damping) and its restitution-damping curve (at CURVE_KN)
TABLE_KNS = (2e8, 2e9, 2e10)
TABLE_DAMPINGS = (0.0, 0.08, 0.3, 0.8)
CURVE_KN = 2e8
CURVE_DAMPINGS = (0.0, 0.02, 0.05, 0.08, 0.15, 0.3, 0.5, 0.8)


def alpha(b: float = B, h: float = H) -> float:
    """Slenderness angle atan(b / h) (rad)."""
    return math.atan2(b, h)


def housner_restitution(b: float = B, h: float = H) -> float:
    """Housner's restitution of the angular velocity of a rigid rectangular block,
    1 - 1.5 sin^2(alpha) (from conservation of angular momentum about the new corner,
    I_O = 4/3 m R^2)."""
    return 1.0 - 1.5 * math.sin(alpha(b, h)) ** 2


def rocking_energy(theta, b: float = B, h: float = H, mass: float = 1.0, g: float = G):
    """Rocking energy (J, for ``mass`` kg) of a rigid block at rest tilted by |theta| (rad)
    on a corner: the rise of its centroid above the upright position times m g,
    R (cos(alpha - theta) - cos(alpha)) written as 2 R sin(alpha - theta/2) sin(theta/2): no
    cancellation near theta = 0, and exactly 0 there on any processor (sin(0) = 0 in every
    implementation, where numpy's cos and the C library's may differ in the last bit)."""
    a = alpha(b, h)
    R = 0.5 * math.hypot(b, h)
    half = 0.5 * np.abs(np.asarray(theta, float))
    return mass * g * R * 2.0 * np.sin(a - half) * np.sin(half)


def frequency_parameter(b: float = B, h: float = H, g: float = G) -> float:
    """p = sqrt(3 g / (4 R)) (rad/s) of a rectangular block."""
    return math.sqrt(3.0 * g / (4.0 * 0.5 * math.hypot(b, h)))


def amplitudes(t, theta) -> np.ndarray:
    """The largest |theta| of each half-cycle (between successive zero crossings of
    theta), each refined by a parabola through the largest sample and its neighbours.
    The first half-cycle starts at the first sample (the release), the last one must end
    with a crossing. Returns (amplitudes rad, times s) as an (n, 2) array."""
    t, th = np.asarray(t, float), np.asarray(theta, float)
    s = np.sign(th)
    cross = np.flatnonzero(s[1:] * s[:-1] < 0) + 1  # first sample after each sign change
    bounds = np.concatenate([[0], cross])
    out = []
    for i0, i1 in zip(bounds[:-1], bounds[1:]):
        seg = np.abs(th[i0:i1])
        k = i0 + int(np.argmax(seg))
        a, tk = abs(th[k]), t[k]
        if i0 < k < i1 - 1:
            y0, y1, y2 = abs(th[k - 1]), abs(th[k]), abs(th[k + 1])
            den = y0 - 2 * y1 + y2
            if den < 0:
                u = 0.5 * (y0 - y2) / den  # vertex offset in samples (equal spacing)
                a = y1 - 0.25 * (y0 - y2) * u
                tk = t[k] + u * (t[k + 1] - t[k])
        out.append((a, tk))
    return np.array(out).reshape(-1, 2)


def sunk_rocking_energy(theta, kn: float, b: float = B, d: float = D, h: float = H, rho: float = RHO,
                        g: float = G):
    """Rocking energy (J) of the block at rest tilted by |theta| (rad) on a corner of a
    penalty (Winkler) contact of stiffness kn (N/m^3), relative to its upright rest: the
    rigid ``rocking_energy`` less what the sunk corner takes. Loaded by its weight W, the
    corner presses a wedge of depth delta = sqrt(2 |theta| W / (kn d)) (volume d delta^2 /
    (2 theta), kn V = W) that holds the elastic energy W delta / 3 and lowers the block by
    delta; upright, the flat joint sinks delta_0 = W / (kn b d) and holds W delta_0 / 2:
    E = m g R [cos(alpha - |theta|) - cos(alpha)] - 2 W delta / 3 + W delta_0 / 2.
    Valid while the wedge is narrower than the base (|theta| > 2 W / (kn d b^2));
    NaN below."""
    th = np.abs(np.asarray(theta, float))
    m = rho * b * d * h
    w = m * g
    delta = np.sqrt(2.0 * th * w / (kn * d))
    e = rocking_energy(th, b, h, m, g) - 2.0 * w * delta / 3.0 + 0.5 * w * w / (kn * b * d)
    return np.where(th > 2.0 * w / (kn * d * b * b), e, np.nan)


def restitution_per_impact(t, theta, b: float = B, h: float = H, min_fraction: float = MIN_AMPLITUDE,
                           sunk: dict | None = None) -> np.ndarray:
    """Restitution r_n = sqrt(E(theta_{n+1}) / E(theta_n)) of each impact of a rocking
    history (theta in rad, about one horizontal axis), while the amplitude after the
    impact exceeds ``min_fraction`` x alpha (smaller ones are hardly rocking on a corner).
    E is the rigid ``rocking_energy``, or with ``sunk`` = {kn, d, rho} the
    ``sunk_rocking_energy`` of the block on its penalty contact."""
    amp = amplitudes(t, theta)[:, 0]
    keep = amp > min_fraction * alpha(b, h)
    n = len(amp) if keep.all() else int(np.argmin(keep))
    if sunk is None:
        e = rocking_energy(amp[:n], b, h)
    else:
        e = sunk_rocking_energy(amp[:n], sunk["kn"], b, sunk["d"], h, sunk["rho"])
    return np.sqrt(e[1:] / e[:-1])


def rigid_rocking(theta0: float, r: float, n_impacts: int, b: float = B, h: float = H, g: float = G,
                  interval: float = 1e-3) -> tuple[np.ndarray, np.ndarray]:
    """Rigid rocking (Housner's equation theta'' = -p^2 sin(alpha sgn(theta) - theta))
    from rest at theta0 (rad), the angular velocity multiplied by r at each impact
    (theta = 0), sampled every ``interval`` s for n_impacts + 2 half-cycles: n_impacts
    impacts between two sampled amplitudes. Integrated with scipy's DOP853 at relative
    tolerance 1e-12. Returns (t s, theta rad)."""
    from scipy.integrate import solve_ivp

    a, p2 = alpha(b, h), frequency_parameter(b, h, g) ** 2

    def f(_, y):
        return [y[1], -p2 * math.sin(a * math.copysign(1.0, y[0]) - y[0])]

    def hit(_, y):
        return y[0]
    hit.terminal, hit.direction = True, 0

    ts, ths = [], []
    t0, y0 = 0.0, [theta0, 0.0]
    for k in range(n_impacts + 2):
        # leave theta = 0 before looking for the next crossing
        y0 = [y0[0] if k == 0 else math.copysign(1e-14, y0[1]), y0[1]]
        sol = solve_ivp(f, (t0, t0 + 100.0), y0, method="DOP853", events=hit, rtol=1e-12, atol=1e-14,
                        dense_output=True)
        te = sol.t_events[0][0]
        grid = np.arange(math.ceil(t0 / interval), math.floor(te / interval) + 1) * interval
        grid = grid[(grid >= t0) & (grid < te)]
        ts.append(grid)
        ths.append(sol.sol(grid)[0])
        t0, y0 = te, [0.0, r * sol.y_events[0][0][1]]
    return np.concatenate(ts), np.concatenate(ths)


# -- the block in YADE ---------------------------------------------------------------------
def block_file(theta0: float, kn: float, damping: float, b: float = B, d: float = D, h: float = H,
               rho: float = RHO, mu: float = MU) -> dict:
    """Block file (drystone.blocks) of the block on a 2 x 2 m platform, tilted by theta0
    (rad, > 0) about its bottom edge x = +b/2 (parallel to y), that edge on the platform."""
    from drystone.geometry import blockfile as bf
    from drystone.geometry import simple

    geo = simple.boxes_on_platform([{"id": 1, "center_xy": [0.0, 0.0], "size": [b, d, h]}], density=rho,
                                   kn=kn, kt=KT_RATIO * kn, mu=mu, damping=damping)
    geo.pop("generator")
    c, s = math.cos(theta0), math.sin(theta0)
    v = np.array(bf.box_vertices((0.0, 0.0, h / 2), (b, d, h))) - [b / 2, 0.0, 0.0]
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # about +y: the -x edge lifts
    geo["blocks"][1]["vertices"] = (v @ rot.T + [b / 2, 0.0, 0.0]).tolist()
    geo["description"] = f"a {b} x {d} x {h} m block tilted {theta0:.4g} rad on its edge x = {b / 2}"
    return geo


def case(name: str, geometry: str, duration: float, interval: float, detection: str = "native") -> dict:
    """Case dict: full gravity at once (no ramp), free rocking for ``duration`` s."""
    return {"case": {"name": name, "geometry": geometry},
            "contact": {"law": "penalty_coulomb", "detection": detection}, "physics": {"gravity": G},
            "stages": [{"type": "gravity", "duration": duration, "ramp": 0.0}],
            "output": {"interval": interval}}


def rock(outdir: Path, kn: float, damping: float, duration: float = DURATION, interval: float = INTERVAL,
         theta0_fraction: float = THETA0_FRACTION, detection: str = "native", b: float = B, d: float = D,
         h: float = H, rho: float = RHO) -> dict:
    """Run the released block (YADE) and return {'t' s, 'theta' rad (the tilt about y,
    > 0 on the release side), 'dt' s, 'wall_s' s, 'slide_m': the largest horizontal
    distance of the base's centre from where it stands upright, at the samples where the
    block is within 1e-3 rad of upright (0 without sliding, up to the corner's sink)}."""
    from drystone import runner
    from drystone.geometry import blockfile as bf
    from drystone.mechanics import rotations
    from drystone.postprocess import summary as summ

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    th0 = theta0_fraction * alpha(b, h)
    name = f"rocking_{kn:g}_{damping:g}"
    bf.write(block_file(th0, kn, damping, b, d, h, rho), outdir / f"{name}.json")
    out = outdir / name
    s = runner.run_dict(case(name, f"{name}.json", duration, interval, detection), outdir / f"{name}.toml",
                        out_dir=out, quiet=True)
    hist = summ.load_histories(out)
    q, q0, pos = hist["quat"][:, 0], hist["quat0"][0], hist["pos"][:, 0]
    theta = th0 + rotations.relative_rotation_vectors(q, q0)[:, 1]
    rel = rotations.to_matrix(q) @ rotations.to_matrix(q0).T  # rotation since the release
    c0, s0 = math.cos(th0), math.sin(th0)
    base0 = np.array([b / 2 - b / 2 * c0, 0.0, b / 2 * s0])  # the base's centre at the release
    base = pos + np.einsum("kij,kj->ki", rel, np.broadcast_to(base0 - pos[0], pos.shape))
    upright = np.abs(theta) < 1e-3
    slide = float(np.abs(base[upright, 0]).max()) if upright.any() else float("nan")
    return {"t": hist["t"], "theta": theta, "dt": json.loads((out / "spec.json").read_text())["dt"],
            "wall_s": s.get("wall_time_total_s"), "slide_m": slide}


def measure(outdir: Path, kn: float, damping: float, n_impacts: int = N_IMPACTS, **kw) -> dict:
    """Restitution of the first ``n_impacts`` impacts of the block released from
    THETA0_FRACTION x alpha at contact stiffness ``kn`` (N/m^3) and damping (fraction of
    critical): {'kn', 'damping', 'r' (per impact), 'amplitude_before_rad',
    'amplitude_after_rad', 'mean',
    'r_sunk' (with ``sunk_rocking_energy``), 'mean_sunk', 'housner', 'dt', 'wall_s',
    'slide_m'}. One YADE run."""
    b, d, h, rho = (kw.get(k, v) for k, v in (("b", B), ("d", D), ("h", H), ("rho", RHO)))
    run = rock(outdir, kn, damping, **kw)
    amp = amplitudes(run["t"], run["theta"])[:, 0]
    r = restitution_per_impact(run["t"], run["theta"], b, h)[:n_impacts]
    rs = restitution_per_impact(run["t"], run["theta"], b, h, sunk={"kn": kn, "d": d, "rho": rho})[:len(r)]
    return {"kn": kn, "damping": damping, "r": r.tolist(), "amplitude_before_rad": amp[:len(r)].tolist(),
            "amplitude_after_rad": amp[1:len(r) + 1].tolist(),
            "mean": float(r.mean()) if len(r) else None, "r_sunk": rs.tolist(),
            "mean_sunk": float(np.mean(rs)) if len(rs) else None, "housner": housner_restitution(b, h),
            "dt": run["dt"], "wall_s": run["wall_s"], "slide_m": run["slide_m"]}


def damping_for_restitution(r_target: float, curve) -> float:
    """The damping (fraction of critical) that gives the restitution ``r_target`` on a
    measured curve [(damping, r), ...] (``curve_rows`` or the report's restitution curve):
    linear interpolation on its decreasing part from damping 0. ValueError if r_target
    is outside the curve's range (the curve says which restitutions the contact can give
    at its K_n)."""
    pts = sorted((float(x), float(y)) for x, y in curve)
    keep = [pts[0]]
    for x, y in pts[1:]:
        if y < keep[-1][1]:
            keep.append((x, y))
        else:
            break
    xs, ys = np.array(keep).T
    if not ys.min() <= r_target <= ys.max():
        raise ValueError(f"restitution {r_target:g} is outside {ys.min():.3f}-{ys.max():.3f}, the range of "
                         f"damping {xs.min():g}-{xs.max():g} at this K_n")
    return float(np.interp(r_target, ys[::-1], xs[::-1]))


def report_section(tmp: Path, kns=TABLE_KNS, dampings=TABLE_DAMPINGS, curve_dampings=CURVE_DAMPINGS,
                   curve_kn: float = CURVE_KN) -> tuple[dict, list[str]]:
    """Run the table (every K_n x damping) and the curve (damping at ``curve_kn``) and
    return (the data for free_decay.json, the Markdown lines for report.md)."""
    runs = {}
    for kn in kns:
        for xi in dampings:
            runs[(kn, xi)] = measure(Path(tmp) / "rocking", kn, xi)
            print(f"rocking restitution K_n {kn:g} damping {xi:g}: "
                  + ", ".join(f"{v:.3f}" for v in runs[(kn, xi)]["r"]), flush=True)
    for xi in curve_dampings:
        if (curve_kn, xi) not in runs:
            runs[(curve_kn, xi)] = measure(Path(tmp) / "rocking", curve_kn, xi)
    rh = housner_restitution()
    a = alpha()
    table = [runs[(kn, xi)] for kn in kns for xi in dampings]
    curve = [[xi, runs[(curve_kn, xi)]["r"][0]] for xi in curve_dampings]
    data = {"block_m": [B, D, H], "density": RHO, "kt_over_kn": KT_RATIO, "mu": MU, "alpha_rad": a,
            "theta0_rad": THETA0_FRACTION * a, "housner": rh, "min_amplitude_rad": MIN_AMPLITUDE * a,
            "table": table, "curve_kn": curve_kn, "curve": curve,
            "measure": "r_n = sqrt(E(theta_n+1) / E(theta_n)), theta_n the rocking amplitudes, E the rigid "
                       "block's rocking energy (drystone/analyses/restitution.py)"}
    n = max(len(t["r"]) for t in table)
    lines = ["", "## Rocking restitution per impact against Housner's rigid block", "",
             f"Block {B} x {D} x {H} m (b x d x h), {RHO:g} kg/m^3, K_t = {KT_RATIO:g} K_n, mu {MU:g}, released "
             f"from rest tilted {THETA0_FRACTION:g} alpha = {THETA0_FRACTION * a:.3f} rad on one bottom edge "
             f"(alpha = atan(b/h) = {a:.4f} rad) and left to rock (drystone/analyses/restitution.py). r_n = "
             "sqrt(E(theta_n+1) / E(theta_n)): the angular-velocity restitution of impact n from the rocking "
             "amplitudes theta_n before and after it (E the rigid block's rocking energy; the energy ratio is "
             f"r^2). Housner's rigid block: r = 1 - 1.5 sin^2(alpha) = {rh:.3f}. Impacts counted while the "
             f"amplitude after them exceeds {MIN_AMPLITUDE:g} alpha; 'sunk' is the mean with the energy less what "
             "the corner's sink into the penalty contact takes.", "",
             "| K_n N/m^3 | damping | " + " | ".join(f"r_{k + 1}" for k in range(n))
             + " | mean | mean, sunk | Housner | slide m |",
             "|---|---|" + "---|" * n + "---|---|---|---|"]
    for t in table:
        cells = [f"{v:.3f}" for v in t["r"]] + ["-"] * (n - len(t["r"]))
        lines.append(f"| {t['kn']:g} | {t['damping']:g} | " + " | ".join(cells)
                     + f" | {_f(t['mean'])} | {_f(t['mean_sunk'])} | {rh:.3f} | {t['slide_m']:.1e} |")
    lines += ["", f"Amplitude before each impact (fraction of alpha) at K_n {curve_kn:g}: "
              + "; ".join(f"damping {t['damping']:g}: " + ", ".join(f"{x / a:.2f}" for x in t["amplitude_before_rad"])
                          for t in table if t["kn"] == curve_kn), "",
              f"### Restitution of the first impact against the damping, K_n {curve_kn:g} N/m^3", "",
              "| damping | " + " | ".join(f"{xi:g}" for xi, _ in curve) + " |",
              "|---|" + "---|" * len(curve), "| r_1 | " + " | ".join(f"{r:.3f}" for _, r in curve) + " |"]
    return data, lines


def _f(v) -> str:
    return "-" if v is None else f"{v:.3f}"
