"""Frequencies and mode shapes of any wall: ``python -m drystone modal CASE``.

1. **Settle.** One run of the case's stages before its first tilt or excitation stage (a
   case without a gravity stage among them gets ``common.GRAVITY`` first, ASSUMED and said
   so), sampled at its end, through the sweeps (resumable: a finished run with the same
   fingerprint is reused). Refused when a stone
   left the model or fell while settling, or still moves at the end (``settled``).
2. **Linearise.** The blocks at the end of that run, a stone of several parts as
   one rigid body of the union's mass properties with one contact per pair of parts
   (drystone/mechanics/modal.py), the stiffness K = -dQ/dq of the project's law there
   (central differences) and the mass matrix M. The recorded state is balanced by shear
   forces the joints stored while settling, which the linear model does not record:
   ``modal.balance`` finds the shear within friction that leaves the least out of balance.
   When a stone stays out of balance by more than ``modal.BALANCE_TOL`` of its weight (the
   run's contact detection and this model's differ where a joint is deep, as YADE's native
   detection on the Sacsayhuaman wall), the modes are those of the nearest equilibrium of
   the joints (``Assembly.equilibrium``: Newton, the tangential springs carrying the shear),
   provided it is reached (to ``modal.BALANCE_TOL``) without opening or closing a contact
   (the contact its springs load most is reported, with its friction use: above 1 the
   linearised joint sticks where the run's would slip); else refused, naming the stone (and
   the contact short of friction): such a wall is not in equilibrium and must be settled (a
   longer gravity stage).
3. **Modes.** eigh(K, M), K symmetrised. Each eigenvalue is read (``modal.interpret``): a
   positive one is a mode (a frequency, its effective mass along x, y, z, its dominant
   direction and stones); one within ``modal.ZERO_EIGENVALUE_REL`` of zero is a motion the
   joints do not resist (a stone touching nothing, say; the twist spring,
   ``contact.twist_spring``, holds a stone twisting on a single joint), listed apart with its
   stone and never as a frequency; a negative one (an unstable equilibrium) refuses the
   analysis, naming the stone.
4. **Check (``--identify``).** A white-noise run after the same settling (``NOISE``:
   band-limited 0-20 Hz, scaled to ``--noise-pga``, ASSUMED small so that the joints stay
   closed) along ``--direction``; the H1 transfer function from the base acceleration to
   the mass-weighted mean displacement of the free stones relative to the base
   (drystone/postprocess/identification.py) and its coherent peaks, set beside the
   linearised modes that move mass along that direction.

Output (results/<case name>/modal/, or --out): modal.json (keys: ``frequencies_hz``, the
first ``--modes`` frequencies, Hz; ``modes``: per mode frequency_hz, period_s,
effective_mass_ratio {x, y, z}, dominant_direction, stones (kinetic-energy share of the
stones moving most); ``zero_modes``: [{explanation, dominant_stone}]; ``model``: DOFs,
contacts, balance; ``settle``, ``identification``, ``timing_s``), modes.png (the first mode
shapes on the wall's elevation) and report.html.
"""
from __future__ import annotations

import time
from pathlib import Path

from drystone.analyses import common

HELP = "frequencies and mode shapes of the settled wall (linearised joints; --identify: a white-noise check)"

#: a stone has settled when its kinetic energy is below 1 % of the elastic energy its weight
#: stores in the joints, (1/2) m g delta (delta the median overlap depth of the wall's
#: contacts): speed below 0.1 sqrt(g delta), a vibration amplitude below a tenth of the
#: static deflection
SETTLED_SPEED_FRACTION = 0.1
#: the finite-difference step of the stiffness (``Assembly.stiffness``), as a fraction of the
#: median overlap depth of the wall's contacts: the stiffness is the secant over vibrations
#: of a tenth of the static deflection. The law's force is not differentiable everywhere:
#: where two neighbours' front faces are coplanar (an extruded wall), an out-of-plane offset
#: of either way thins their overlap, a force step of F_n x depth / thickness, which central
#: differences over a step h read as a spurious negative stiffness F_n depth / (thickness h)
#: (at 1e-3 of the depth: negative eigenvalues on a settled wall of re-entrant stones,
#: cases/examples/polygonal_wall.toml; at 0.1 a few % of the joints' shear stiffness);
#: ``Assembly.stiffness`` now leaves such a step out (drystone/mechanics/modal.py), and 0.1
#: stays the secant's amplitude. On a closed flat joint the forces are linear in the translations and the
#: rotations' geometric terms err by O((h / stone size)^2): 1e-6 on the Winkler block
#: (tests/test_analyses_modal.py). ``STEP_CHECK``: the frequencies again at these multiples
#: of the step, their largest relative change reported (``model.step_sensitivity``)
STEP_REL = 0.1
STEP_CHECK = (1 / 3, 3.0)
#: a friction use above 1 (``modal.balance``) beyond the linear programme's tolerance: a
#: contact short of friction, named when a stone is out of balance
FRICTION_SLACK = 1e-6
#: the white-noise check (ASSUMED): 0-20 Hz band-limited noise (drystone.motions.generators),
#: scaled to a PGA small enough that the joints stay closed; the run's output sampled at
#: 200 Hz (10 samples per period at 20 Hz); H1 with Hann segments of the largest power of 2
#: giving at least 7 averages (50 % overlap); peaks 0.1 decade out of |H| with coherence >= 0.9
NOISE = {"pga_g": 0.05, "duration_s": 20.0, "interval_s": 0.005, "fmax_hz": 20.0, "coherence_min": 0.9,
         "prominence_decades": 0.1, "min_segments": 7}
#: a linearised mode takes part in the check when its effective mass along the noise's
#: direction is at least this fraction of the wall's
PARTICIPATING = 0.05


def add_arguments(p) -> None:
    common.add_common_arguments(p)
    p.add_argument("--modes", type=int, default=6, help="modes to report (default 6)")
    p.add_argument("--identify", action="store_true",
                   help="also a white-noise run and its transfer function, as a check of the frequencies")
    p.add_argument("--direction", choices=("x", "y", "z"), default="y",
                   help="direction of the white noise (default y, out of plane)")
    p.add_argument("--noise-pga", type=float, default=NOISE["pga_g"], metavar="G",
                   help=f"PGA of the white noise, g (default {NOISE['pga_g']}, ASSUMED)")
    p.add_argument("--noise-duration", type=float, default=NOISE["duration_s"], metavar="S",
                   help=f"length of the white noise, s (default {NOISE['duration_s']:g})")


def main(args) -> int:
    backend, address = common.backend_of(args)
    r = modal(args.case, out=args.out, modes=args.modes, identify=args.identify, direction=args.direction,
              noise_pga_g=args.noise_pga, noise_duration_s=args.noise_duration, workers=args.workers,
              backend=backend, address=address)
    f = ", ".join(f"{x:.3g}" for x in r["frequencies_hz"])
    print(f"[modal] frequencies (Hz): {f}; results in {r['out_dir']}")
    if r["zero_modes"]:
        print(f"[modal] {len(r['zero_modes'])} motion(s) without stiffness (not frequencies): "
              + "; ".join(z["explanation"] for z in r["zero_modes"][:3]))
    idn = r["identification"]
    if idn and "peak_model_hz" in idn:
        print(f"[modal] white-noise check along {idn['direction']}: |H| peaks at {idn['peak_identified_hz']:.3g} Hz "
              f"(linearised model with its dashpots: {idn['peak_model_hz']:.3g} Hz), |H| identified / model "
              f"{idn['h_ratio_median']:.3f} (median over the coherent band)")
    elif idn:
        print(f"[modal] white-noise check along {idn['direction']}: no coherent band, nothing to compare")
    return 0


# -- the settling run ----------------------------------------------------------------------

def settle_stages(case_path, overrides=()) -> tuple[list, bool]:
    """The stages that settle the wall: the case's stages before its first tilt or
    excitation stage, with ``common.GRAVITY`` first if they have no gravity stage
    (``common.stages_before``); and whether that gravity stage was added."""
    pre = common.stages_before(case_path, overrides)
    from drystone import inputfiles
    from drystone.model import case as casemod

    raw = inputfiles.load_toml(Path(case_path), casemod.CaseError, "case file")
    own = []
    for st in raw.get("stages", []):
        if st.get("type") in ("tilt", "excitation"):
            break
        own.append(st)
    return pre, not any(st.get("type") == "gravity" for st in own)


def stages_override(stages: list) -> str:
    """The --set override replacing the case's stages by ``stages``."""
    from drystone import tomlio

    return f"stages={tomlio.value(stages)}"


def settled(run_dir, asm) -> dict:
    """The free stones' speeds at the sample the modes are taken at: {"speed_m_s": largest,
    "stone", "limit_m_s": SETTLED_SPEED_FRACTION sqrt(g delta), "settled": bool}; and the
    stones that fell while settling (their centroid dropped by more than half their height
    since t = 0, the collapse rule of drystone/analyses/common.py): "fell": [ids]."""
    import numpy as np

    from drystone.postprocess import summary as summ

    h = summ.load_histories(run_dir)
    i = int(np.argmin(np.abs(np.asarray(h["t"]) - asm.sample_time_s)))
    v = np.linalg.norm(np.asarray(h["vel"])[i], axis=1)
    rc = asm.reference_contacts
    delta = float(np.median(rc["volume"] / rc["area"])) if len(rc["volume"]) else 0.0
    limit = SETTLED_SPEED_FRACTION * float(np.sqrt(np.linalg.norm(asm.gravity) * delta))
    j = int(np.argmax(v)) if len(v) else 0
    ids = [int(b) for b in h["block_ids"]]
    drop = np.asarray(h["pos"])[0, :, 2] - np.asarray(h["pos"])[i, :, 2]
    height = [float(np.ptp(np.vstack(asm.parts[asm.ids.index(b)])[:, 2])) for b in ids]
    fell = [b for b, dz, hh in zip(ids, drop, height) if dz > 0.5 * hh]
    return {"fell": fell, "speed_m_s": float(v[j]) if len(v) else 0.0,
            "stone": int(h["block_ids"][j]) if len(v) else None, "limit_m_s": limit,
            "settled": bool(len(v) == 0 or v[j] <= limit), "time_s": float(h["t"][i])}


# -- the linearised modes -------------------------------------------------------------------

def analyse(asm, modes: int = 6, where: str = "wall", rel_step: float = STEP_REL) -> dict:
    """The modal analysis of an ``Assembly`` at its static configuration (steps 2-3 of the
    module docstring): {"frequencies_hz", "modes", "zero_modes", "model", "_res", "_all"}
    (``_res``: ``Assembly.modes``' arrays, for the figure; ``_all``: every mode's row).
    RunError (one line, naming the stone or contact) for a wall out of balance or in
    unstable equilibrium."""
    import numpy as np

    from drystone.mechanics import modal as mm
    from drystone.simulate import RunError

    if len(asm.reference_contacts["volume"]) == 0:
        raise RunError(f"{where}: no stone touches another: nothing holds the wall")
    bal = mm.balance(asm)
    at = np.zeros(asm.ndof)
    nearby = None
    if not bal["balanced"]:
        use = bal["friction_use"]
        why = "" if use is None or use <= 1 + FRICTION_SLACK else \
            f" (the contact of stones {bal['friction_contact'][0]} and {bal['friction_contact'][1]} would need " \
            f"{use:.3g} times its friction)"
        unbalanced = (f"stone {bal['residual_stone']} is out of balance by {100 * bal['residual']:.2g} % of its weight "
                      f"with its joints carrying shear within friction{why}")
        q, hist = asm.equilibrium(rel_step=rel_step)
        same = _pairs(asm, q) == _pairs(asm, at)
        if hist[-1] > mm.BALANCE_TOL or not same:
            raise RunError(f"{where}: {unbalanced}, and no equilibrium of the joints is near"
                           + ("" if same else " without opening or closing a contact")
                           + ": the wall is not in equilibrium; settle it (a longer gravity stage) and rerun")
        # the springs may carry more than friction there: said, not refused (the run, settled,
        # holds the wall; its stored shear and contact detection are what this model lacks)
        use, pair = asm.friction_use(q) if asm.mu is not None else (0.0, None)
        at = q
        tr = [abs(v) for (b, c), v in zip(asm.dofs, q) if c < 3]
        nearby = {"reason": unbalanced, "residual": float(hist[-1]), "iterations": len(hist) - 1,
                  "max_translation_m": float(max(tr, default=0.0)), "friction_use": use,
                  "friction_contact": list(pair) if pair else None}
    res = asm.modes(rel_step=rel_step, at=at)
    info = mm.interpret(asm, res)
    order = np.argsort(res["frequency_hz"])
    unstable = [info["eigen"][k] for k in order if info["eigen"][k]["kind"] == "unstable"]
    if unstable:
        raise RunError(f"{where}: {len(unstable)} negative eigenvalue(s): {unstable[0]['explanation']}; the settled "
                       "state is not a stable equilibrium: settle it (a longer gravity stage) and rerun")
    table, zero = [], []
    for k in order:
        e = info["eigen"][k]
        if e["kind"] == "zero":
            zero.append({"explanation": e["explanation"], "dominant_stone": e["dominant_stone"],
                         "eigenvalue_rad2_s2": e["eigenvalue_rad2_s2"]})
            continue
        f = float(res["frequency_hz"][k])
        em = e["effective_mass_ratio"]
        top = max(em, key=em.get)
        motion = max(e["motion_share"], key=e["motion_share"].get)
        stones = {str(b): round(s, 4) for b, s in list(e["stone_share"].items())[:3]}
        table.append({"mode": len(table) + 1, "frequency_hz": f, "period_s": 1.0 / f,
                      "effective_mass_ratio": em, "dominant_direction": top if em[top] >= 0.01 else None,
                      "dominant_motion": mm.MOTION[motion], "stones": stones, "index": int(k)})
    n = min(int(modes), len(table))
    sens = {}
    for x in STEP_CHECK:
        f = np.sort(asm.modes(rel_step=rel_step * x, at=at)["frequency_hz"])
        f = f[f > 0][-len(table):]  # as many positive ones as there are modes, the highest
        ref = np.array([m["frequency_hz"] for m in table[:n]])
        # None: fewer positive eigenvalues at that step (a negative one appeared)
        sens[f"{rel_step * x:.3g}"] = float(np.max(np.abs(f[:n] / ref - 1))) if n and len(f) == len(table) else None
    total = {a: float(sum(m["effective_mass_ratio"][a] for m in table[:n])) for a in "xyz"}
    rc = asm.reference_contacts
    model = {"free_stones": int(asm.moving.sum()), "multi_part_stones": [asm.ids[b] for b, p in enumerate(asm.parts)
                                                                          if len(p) > 1 and asm.moving[b]],
             "ndof": asm.ndof, "contacts": int(len(rc["volume"])), "contacts_per_stone": info["contacts"],
             "median_overlap_depth_m": float(np.median(rc["volume"] / rc["area"])),
             "asymmetry": res["asymmetry"], "zero_eigenvalue_rel": mm.ZERO_EIGENVALUE_REL,
             "step_rel": rel_step, "step_sensitivity": sens,
             "balance": {k: (list(v) if isinstance(v, tuple) else v) for k, v in bal.items()},
             "nearby_equilibrium": nearby,
             "all_frequencies_hz": [m["frequency_hz"] for m in table]}
    return {"frequencies_hz": [m["frequency_hz"] for m in table[:n]], "modes": table[:n], "zero_modes": zero,
            "cumulative_effective_mass_ratio": total, "model": model, "_res": res, "_all": table}


def _pairs(asm, q) -> set:
    """The pairs of parts in contact at the configuration q."""
    c = asm.contacts(q)
    return set(zip(c["id1"].tolist(), c["id2"].tolist()))


# -- the white-noise check ------------------------------------------------------------------

def identification(run_dir, asm, direction: str, model=None) -> dict:
    """The H1 transfer function base acceleration -> mass-weighted mean displacement of the
    free stones relative to the base, along ``direction``, during a white-noise run, and its
    coherent peaks (``NOISE``). With ``model`` = (K, C, M) the linearised model's own
    transfer function of the same quantity (``Assembly.frequency_response``: contact
    dashpots as the dynamic law applies them, every contact sticking) at the same
    frequencies, the peak of each in the coherent band, and the ratio |H identified| /
    |H model| over that band (median, and its range)."""
    import numpy as np

    from drystone.postprocess import identification as idf
    from drystone.postprocess import summary as summ

    comp = "xyz".index(direction)
    h = summ.load_histories(run_dir)
    b = idf.base_motion(run_dir)
    t = np.asarray(h["t"])
    win = (t >= b["start"]) & (t <= min(b["end"], b["t"][-1]))
    ids = [int(i) for i in h["block_ids"]]
    mass = np.array([asm.mass[asm.ids.index(i)] for i in ids])
    pos = np.asarray(h["pos"])[win][:, :, comp]
    rel = (pos - pos[0]) @ mass / mass.sum()
    acc = np.interp(t[win], b["t"], b["acc"]) * float(b["direction"][comp])
    fs = 1.0 / float(np.median(np.diff(t[win])))
    nseg = 2 ** int(np.floor(np.log2(2 * len(rel) / (NOISE["min_segments"] + 1))))
    tf = idf.transfer_function(acc, rel, fs, nseg)
    fmin = max(0.3, 2.0 / (nseg / fs))  # two cycles per segment at least
    peaks = idf.modal_peaks(tf, coherence_min=NOISE["coherence_min"], fmin_hz=fmin, fmax_hz=NOISE["fmax_hz"],
                            prominence=NOISE["prominence_decades"])
    f = np.asarray(tf["freq_hz"])
    band = (f >= fmin) & (f <= NOISE["fmax_hz"]) & (np.asarray(tf["coherence"]) >= NOISE["coherence_min"])
    out = {"direction": direction, "fs_hz": fs, "nperseg": int(nseg), "n_segments": tf["n_segments"],
           "df_hz": tf["df_hz"], "band_hz": [fmin, NOISE["fmax_hz"]], "coherent_bins": int(band.sum()),
           "peaks": [{"frequency_hz": p["frequency_hz"], "coherence": p["coherence"],
                      "damping_ratio": p["damping_ratio"]} for p in peaks], "_tf": tf}
    if band.any():
        k = int(np.flatnonzero(band)[np.argmax(np.abs(tf["H"][band]))])
        out["peak_identified_hz"] = float(f[k])
    if model is not None and band.any():
        K, C, M = model
        w = np.array([float(m) if asm.moving[b] and c == comp else 0.0
                      for (b, c), m in zip(asm.dofs, (asm.mass[b] for b, _ in asm.dofs))]) / mass.sum()
        hm = np.array([w @ x for x in asm.frequency_response(K, C, M, f[band], np.eye(3)[comp])])
        fine = np.linspace(fmin, NOISE["fmax_hz"], 400)
        hf = np.abs([w @ x for x in asm.frequency_response(K, C, M, fine, np.eye(3)[comp])])
        ratio = np.abs(tf["H"][band]) / np.abs(hm)
        out.update(peak_model_hz=float(fine[int(np.argmax(hf))]), h_ratio_median=float(np.median(ratio)),
                   h_ratio_range=[float(ratio.min()), float(ratio.max())],
                   _model=(f[band], hm))
    return out


def damping_of(run_dir, asm) -> list:
    """Each block's contact damping ratio (fraction of critical) from a run's spec.json."""
    import json

    spec = json.loads((Path(run_dir) / "spec.json").read_text())
    by = {b["id"]: spec["materials"][b["material"]].get("damping", 0.0) for b in spec["blocks"]}
    return [float(by[i]) for i in asm.ids]


def transfer_figure(ident: dict, path) -> Path:
    """|H| identified (with its coherence) and of the linearised model, against frequency."""
    import os

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    path = Path(path)
    tf = ident["_tf"]
    f = np.asarray(tf["freq_hz"])
    keep = (f > 0) & (f <= 1.5 * NOISE["fmax_hz"])
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.5, 4.6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    a1.semilogy(f[keep], np.abs(tf["H"][keep]), "k-", lw=1, label="white-noise run (H1)")
    if "_model" in ident:
        fm, hm = ident["_model"]
        a1.semilogy(fm, np.abs(hm), "r--", lw=1, label="linearised model (contact dashpots)")
    a1.set_ylabel("|H| (s^2)")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3, which="both")
    a1.set_title(f"base acceleration -> mean relative displacement along {ident['direction']}", fontsize=9)
    a2.plot(f[keep], tf["coherence"][keep], "b-", lw=1)
    a2.axhline(NOISE["coherence_min"], color="0.5", lw=0.8, ls=":")
    a2.set_ylabel("coherence")
    a2.set_xlabel("frequency (Hz)")
    a2.set_ylim(0, 1.05)
    fig.tight_layout()
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)
    return path


def compare(table: list, peaks: list, direction: str, fmax_hz: float) -> list:
    """Per linearised mode with effective mass >= PARTICIPATING along ``direction`` below
    ``fmax_hz``: the identified peak paired with it (each peak goes to its nearest such mode,
    a mode keeps the nearest of its peaks) and the difference (%); None where no peak pairs
    with the mode."""
    rows = [m for m in table if m["effective_mass_ratio"][direction] >= PARTICIPATING and m["frequency_hz"] <= fmax_hz]
    pair = {}
    for p in peaks:
        if rows:
            m = min(rows, key=lambda m: abs(p["frequency_hz"] - m["frequency_hz"]))
            gap = abs(p["frequency_hz"] - m["frequency_hz"])
            if m["mode"] not in pair or gap < abs(pair[m["mode"]] - m["frequency_hz"]):
                pair[m["mode"]] = p["frequency_hz"]
    return [{"mode": m["mode"], "linearised_hz": m["frequency_hz"],
             "effective_mass_ratio": m["effective_mass_ratio"][direction], "identified_hz": pair.get(m["mode"]),
             "difference_pct": 100 * (pair[m["mode"]] / m["frequency_hz"] - 1) if m["mode"] in pair else None}
            for m in rows]


# -- figure ----------------------------------------------------------------------------------

def figure(asm, res: dict, table: list, path, panels: int = 4) -> Path:
    """The first ``panels`` mode shapes on the wall's elevation (x along the wall, z up): each
    stone's parts displaced along the mode (u + theta x r, scaled so that the largest
    displacement is 8 % of the wall's height) over the stones at rest (grey outlines),
    coloured by the out-of-plane (y) displacement of their centroid."""
    import os

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Polygon
    from scipy.spatial import ConvexHull

    path = Path(path)
    shown = table[:panels]
    free = np.flatnonzero(asm.moving)
    pts = np.vstack([v for b in free for v in asm.parts[b]])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    height = float(hi[2] - lo[2]) or 1.0
    ncol = max(1, min(2, len(shown)))
    nrow = max(1, int(np.ceil(len(shown) / ncol)))
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.0 * ncol, 3.2 * nrow + 0.4), squeeze=False,
                             constrained_layout=True)
    cmap = plt.get_cmap("coolwarm")

    def outline(v):
        p = v[:, [0, 2]]
        try:
            return p[ConvexHull(p).vertices]
        except Exception:  # noqa: BLE001 - a part seen edge-on: its extent as a segment
            return p[[int(np.argmin(p[:, 0])), int(np.argmax(p[:, 0]))]]

    for ax, m in zip(axes.flat, shown):
        phi = res["shapes"][:, m["index"]]
        disp = {b: (lambda pts_, b=b: np.array([asm.point_displacement(phi, asm.ids[b], x) for x in pts_]))
                for b in free}
        dmax = max(float(np.abs(disp[b](np.vstack(asm.parts[b]))).max()) for b in free) or 1.0
        scale = 0.08 * height / dmax
        uy = {b: float(asm.point_displacement(phi, asm.ids[b], asm.pos0[b])[1]) * scale / (0.08 * height)
              for b in free}
        for b in range(len(asm.parts)):
            for v in asm.parts[b]:
                if asm.moving[b]:
                    ax.add_patch(Polygon(outline(v), closed=True, fill=False, ec="0.6", lw=0.6, ls="--"))
                    dv = v + scale * disp[b](v)
                    ax.add_patch(Polygon(outline(dv), closed=True, fc=cmap(0.5 + 0.5 * uy[b]), ec="k", lw=0.6))
                else:
                    ax.add_patch(Polygon(outline(v), closed=True, fc="0.8", ec="0.5", lw=0.5))
        for b in free:
            ax.annotate(str(asm.ids[b]), (asm.pos0[b][0], asm.pos0[b][2]), fontsize=6, ha="center", va="center",
                        color="0.3")
        pad = 0.1 * max(hi[0] - lo[0], height)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[2] - pad, hi[2] + pad)
        ax.set_aspect("equal")
        d = m["dominant_direction"]
        em = f", {100 * m['effective_mass_ratio'][d]:.0f} % of the mass along {d}" if d else \
            f", {m['dominant_motion']} (stones {', '.join(list(m['stones'])[:2])})"
        ax.set_title(f"mode {m['mode']}: {m['frequency_hz']:.3g} Hz{em}", fontsize=9)
        ax.set_xlabel("x (m)", fontsize=8)
        ax.set_ylabel("z (m)", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(shown):]:
        ax.axis("off")
    fig.suptitle("mode shapes on the elevation (dashed: at rest; colour: out-of-plane y displacement, blue - / "
                 "red +, relative)", fontsize=9)
    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)
    return path


# -- the analysis -----------------------------------------------------------------------------

def modal(case, out=None, modes: int = 6, identify: bool = False, direction: str = "y",
          noise_pga_g: float = NOISE["pga_g"], noise_duration_s: float = NOISE["duration_s"], workers=None,
          backend: str = "local", address=None, overrides=(), log=print) -> dict:
    """Frequencies and mode shapes of ``case`` (module docstring), with the case-key
    ``overrides`` (``--set`` strings); returns what modal.json holds."""
    import numpy as np

    from drystone.postprocess import identification as idf
    from drystone.simulate import RunError
    from drystone.model import case as casemod

    case_path = Path(case).expanduser().resolve()
    casemod.load(case_path, list(overrides))  # a bad case or override is refused before anything runs
    if modes < 1:
        raise casemod.CaseError(f"{case_path}: --modes must be at least 1, got {modes}")
    if identify and not (noise_pga_g > 0 and noise_duration_s > 0):
        raise casemod.CaseError(f"{case_path}: --noise-pga and --noise-duration must be positive")
    d = common.output_dir(case_path, "modal", out)
    stages, added = settle_stages(case_path, overrides)
    runs = [("settle", [stages_override(stages)])]
    if identify:
        noise = {"type": "excitation", "motion": "white_noise", "duration": float(noise_duration_s), "seed": 0,
                 "direction": direction, "pga_g": float(noise_pga_g)}
        runs.append((f"white_noise_{direction}", [stages_override(stages + [noise]),
                                                  f"output.interval={NOISE['interval_s']!r}"]))
    t0 = time.time()
    done = common.run_jobs(case_path, runs, d, "modal", list(overrides), workers=workers, backend=backend,
                           address=address, log=log)
    t_runs = time.time() - t0
    st = done["settle"]
    where = str(case_path)
    if st["status"] != "done":
        raise RunError(f"{where}: the settling run failed: {st.get('error')}")
    if st["collapsed"]:
        raise RunError(f"{where}: stone(s) {st['collapsed_stones']} collapsed while settling under gravity: the wall "
                       "does not stand; no modes")
    run_dir = Path(st["run_dir"])
    t1 = time.time()
    from drystone.postprocess import summary as summ

    asm = idf.wall_assembly(run_dir, time_s=float(np.asarray(summ.load_histories(run_dir)["t"])[-1]))
    rest = settled(run_dir, asm)
    if rest["fell"]:
        raise RunError(f"{where}: stone(s) {rest['fell']} fell while settling under gravity: the wall does not stand; "
                       "no modes")
    if not rest["settled"]:
        raise RunError(f"{where}: stone {rest['stone']} still moves at {rest['speed_m_s']:.3g} m/s at the end of "
                       f"settling ({rest['time_s']:.3g} s; settled below {rest['limit_m_s']:.2g} m/s): the wall has "
                       "not settled; lengthen its gravity stage (or add a rest stage after it) and rerun")
    r = analyse(asm, modes, where)
    res = r.pop("_res")
    rows = r.pop("_all")
    t_modal = time.time() - t1
    fig = figure(asm, res, r["modes"], d / "modes.png")
    figs = [fig]
    ident = None
    if identify:
        wn = done[runs[1][0]]
        if wn["status"] != "done":
            raise RunError(f"{where}: the white-noise run failed: {wn.get('error')}")
        K, M = 0.5 * (res["K"] + res["K"].T), res["M"]
        C = asm.damping(damping_of(run_dir, asm))
        ident = identification(Path(wn["run_dir"]), asm, direction, (K, C, M))
        figs.append(transfer_figure(ident, d / "transfer.png"))
        ident.pop("_tf")
        ident.pop("_model", None)
        fd, zd, _ = asm.damped_modes(K, C, M)
        ident["damped_modes"] = [{"frequency_hz": float(a), "damping_ratio": float(z)} for a, z in zip(fd[:modes],
                                                                                                       zd[:modes])]
        ident.update(pga_g=float(noise_pga_g), duration_s=float(noise_duration_s), run_dir=wn["run_dir"],
                     collapsed=wn["collapsed"], largest_residual_m=wn["largest_residual_m"],
                     comparison=compare(rows, ident["peaks"], direction, NOISE["fmax_hz"]),
                     assumed="white noise 0-20 Hz, its PGA and length (ASSUMED)")
    data = {"case": str(case_path), "analysis": "modal", "out_dir": str(d), **r, "identification": ident,
            "settle": {"run_dir": str(run_dir), "gravity_stage": "added (ASSUMED: " + str(common.GRAVITY) + ")"
                       if added else "the case's", "sample_time_s": asm.sample_time_s, "rest": rest,
                       "wall_s": st.get("wall_s")},
            "timing_s": {"runs": t_runs, "modal": t_modal, "total": time.time() - t0},
            "units": {"frequency": "Hz", "period": "s", "effective_mass_ratio": "fraction of the free stones' mass",
                      "eigenvalue": "rad^2/s^2"}}
    for m in rows:
        m.pop("index", None)
    common.write_json(d / "modal.json", data)
    common.write_report(d, f"Modes of {case_path.name}", report(data), figs)
    log(f"[modal] {d / 'modal.json'}, {', '.join(f.name for f in figs)}, report.html")
    return data


def _balance_text(b: dict) -> str:
    """The balance of the recorded state in words (``modal.balance``'s dict)."""
    if b["balanced"]:
        text = (f"Balance: the joints' shear within friction balances every stone to {b['residual']:.1e} of its "
                f"weight (as built, without it: {b['as_built_residual']:.2g})")
    else:
        text = (f"Balance: with the joints' shear within friction, stone {b['residual_stone']} stays out of balance "
                f"by {b['residual']:.2g} of its weight (as built, without shear: {b['as_built_residual']:.2g})")
    use = b["friction_use"]
    if use is None:
        return text + "."
    text += f"; balancing every stone takes at least {use:.2f} of the friction of one contact"
    if use > 0.95:
        text += (" (at its limit: the linearised joints stick, so a mode that shears that contact is stiffer than "
                 "the wall in anything but the smallest motions)")
    return text + "."


def report(data: dict) -> str:
    """report.html's Markdown."""
    m = data["model"]
    lines = [f"# Modes of {Path(data['case']).name}", "",
             f"Linearised joints at the settled state ({data['settle']['gravity_stage']} gravity stage, sampled at "
             f"{data['settle']['sample_time_s']:.3g} s): {m['free_stones']} free stones "
             f"({len(m['multi_part_stones'])} of several parts), {m['ndof']} DOFs, {m['contacts']} contacts (pairs of "
             f"parts). " + _balance_text(m["balance"]), "",
             *([f"The recorded state is not balanced this way ({m['nearby_equilibrium']['reason']}): the modes are "
                f"those of the nearest equilibrium of the joints (their tangential springs unlimited; "
                f"{m['nearby_equilibrium']['iterations']} Newton steps, residual "
                f"{m['nearby_equilibrium']['residual']:.1e} of a stone's weight, stones moved by at most "
                f"{1e6 * m['nearby_equilibrium']['max_translation_m']:.3g} um, no contact opened or closed; the most "
                f"used contact, of stones {m['nearby_equilibrium']['friction_contact']}, at "
                f"{m['nearby_equilibrium']['friction_use']:.2f} of its friction"
                + (": above 1, the linearised joints stick where the run's would slip)." if
                   m['nearby_equilibrium']['friction_use'] > 1 else ")."), ""]
               if m.get("nearby_equilibrium") else []),
             f"Stiffness by central differences over {m['step_rel']:g} of the median overlap depth "
             f"({m['median_overlap_depth_m']:.2g} m); at other steps these frequencies change by at most: "
             + ", ".join(f"{100 * v:.1f} % (step {k})" if v is not None else f"- (step {k}: a negative eigenvalue)"
                         for k, v in m["step_sensitivity"].items()) + ".", "",
             "| mode | f (Hz) | T (s) | eff. mass x | eff. mass y | eff. mass z | dominant | stones (share) |",
             "|---:|---:|---:|---:|---:|---:|---|---|"]
    for r in data["modes"]:
        em = r["effective_mass_ratio"]
        st = ", ".join(f"{b} ({100 * s:.0f} %)" for b, s in r["stones"].items())
        lines.append(f"| {r['mode']} | {r['frequency_hz']:.4g} | {r['period_s']:.4g} | {em['x']:.3f} | {em['y']:.3f} | "
                     f"{em['z']:.3f} | {r['dominant_direction'] or '-'}, {r['dominant_motion']} | {st} |")
    c = data["cumulative_effective_mass_ratio"]
    lines += ["", f"Cumulative effective mass of these modes: x {c['x']:.2f}, y {c['y']:.2f}, z {c['z']:.2f}.", ""]
    if data["zero_modes"]:
        lines += ["Motions without stiffness (not frequencies):", ""]
        lines += [f"- {z['explanation']}" for z in data["zero_modes"]] + [""]
    idn = data["identification"]
    if idn:
        pk = ", ".join(f"{p['frequency_hz']:.3g}" for p in idn["peaks"]) or "none"
        lines += ["## White-noise check", "",
                  f"White noise along {idn['direction']}, {idn['pga_g']:g} g, {idn['duration_s']:g} s "
                  f"({idn['assumed']}); H1 transfer function base acceleration -> mean relative displacement, "
                  f"{idn['n_segments']} segments of {idn['nperseg']} samples ({idn['df_hz']:.3g} Hz bins). Coherent "
                  f"peaks standing out of |H| (Hz): {pk}.",
                  "",
                  (f"Peak of |H| in the coherent band: {idn['peak_identified_hz']:.3g} Hz identified, "
                   f"{idn['peak_model_hz']:.3g} Hz from the linearised model with the contact dashpots; |H| identified "
                   f"/ model: median {idn['h_ratio_median']:.3f} (range {idn['h_ratio_range'][0]:.3f}-"
                   f"{idn['h_ratio_range'][1]:.3f}). Damped modes of the model (Hz, damping ratio): "
                   + ", ".join(f"{m['frequency_hz']:.3g} ({m['damping_ratio']:.2f})" for m in idn["damped_modes"])
                   + ".") if "peak_model_hz" in idn else "No coherent band: nothing to compare.", "",
                  "![transfer](transfer.png)", "",
                  "| mode | linearised (Hz) | eff. mass | identified (Hz) | difference |", "|---:|---:|---:|---:|---:|"]
        for row in idn["comparison"]:
            ih = "-" if row["identified_hz"] is None else f"{row['identified_hz']:.4g}"
            dp = "-" if row["difference_pct"] is None else f"{row['difference_pct']:+.1f} %"
            lines.append(f"| {row['mode']} | {row['linearised_hz']:.4g} | {row['effective_mass_ratio']:.2f} | {ih} | "
                         f"{dp} |")
        lines.append("")
    t = data["timing_s"]
    lines += [f"Time: runs {t['runs']:.0f} s, modal analysis {t['modal']:.1f} s.", "", "![modes](modes.png)", ""]
    return "\n".join(lines)
