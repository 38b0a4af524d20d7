"""``results/crosscheck/report.md`` and figures from ``crosscheck.json`` (no simulation).

Per case: what each engine computed, the closed forms, the convergence table (this
package at each K_n against LMGC90's rigid value, the closed forms beside) and a figure of
the quantity against K_n with LMGC90's value as the asymptote (left) and the difference to
it on log-log axes (right: the convergence rate).
"""
from __future__ import annotations

from pathlib import Path

from drystone import atomic
from drystone.postprocess import markdown
from drystone.studies.crosscheck import VERSION, cases, engine, study, translate

FIG_SIZE = (10.0, 4.0)  # in
FIG_DPI = 100

ASSUMED = [
    "LMGC90 runs the rigid limit: contact law IQS_CLB (Signorini condition, Coulomb friction with the block file's "
    "mu, restitution 0); the block file's K_n, K_t and damping are not used by it (ASSUMED: the limit of the "
    "penalty law as K_n, K_t grow).",
    "LMGC90 contact detection: the common-plane method (LMGC90's 'CpCundall', chosen through the library's private "
    "switch, drystone/studies/crosscheck/engine.py); compas_lmgc90's own choice (face-to-face 'STO') loses the contact of "
    "a block rocking on an edge (checked: the toppling block falls through the platform once it rocks). Exception: "
    "the Santa-Cruz tilt walls, whose irregular stones the common-plane method does not hold at all (they fall "
    "through each other from the first step), run with 'STO', valid up to the onset of rocking (ASSUMED adequate "
    "for the onset angle).",
    "LMGC90 time integration: Moreau-Jean theta method, theta = 0.5; its Gauss-Seidel solver's tolerance and "
    "iteration counts are fixed inside compas_lmgc90 0.1.11 (not settable).",
    "Gravity tilt: in both engines the platform frame is used, gravity rotated by the tilt, the rotation's own "
    "inertial forces neglected (docs/physics.md, Platform frame); in LMGC90 gravity is written into its module variables "
    "before every step at the middle of the step.",
    "Half-sine pulse: LMGC90 moves the platform with the pulse's velocity history (a moving base); this package "
    "applies -a_b as a body force in the platform frame.",
    f"Toppling block: the package's contact damping is {cases.TOPPLE_DAMPING} of critical (ASSUMED, light: a heavily "
    "damped run-away is dated later by the onset rule; docs/physics.md).",
    "Collapse angles of both engines are read with the package's rule (drystone/mechanics/collapse.py: the onset of a motion "
    "of 5 mm per degree of tilt over 0.2 deg windows); a rigid block that starts to move at atan(b/h) reaches that "
    "rate a little later, which the rigid rocking equation with the same programme and rule gives.",
]


def _f(v, nd=4) -> str:
    if v is None:
        return "-"
    if isinstance(v, str):
        return v
    return f"{v:.{nd}f}" if abs(v) >= 1e-3 or v == 0 else f"{v:.4g}"


def _value_str(entry, v) -> str:
    if v is None:
        return "-"
    return f"{v * 1e3:.3f} mm" if entry["quantity"] == "slide_m" else f"{v:.3f} deg"


def _asymptote(entry):
    lm = entry.get("lmgc90") or {}
    return lm.get("value")


def _closed_rows(entry) -> list[tuple[str, object]]:
    cf = entry.get("closed_forms") or {}
    rows = []
    if entry["name"] == "toppling":
        rows.append(("rigid block, atan(b/h)", cf.get("rigid_deg")))
        rows.append(("rigid rocking equation, same programme, package's onset rule", cf.get("rigid_with_rule_deg")))
    elif entry["name"] == "pulse":
        rp = cf.get("rigid_plastic") or {}
        rows.append(("rigid-plastic slide, continuous half-sine (closed form)", rp.get("slide_m")))
        rs = cf.get("rigid_plastic_as_sampled") or {}
        rows.append(("rigid-plastic slide, the pulse as applied (package's samples)", rs.get("slide_m")))
    elif entry["name"] == "wall":
        rows.append(("free courses as one rigid body, atan(t / H_free) (ASSUMED mechanism)", cf.get("rigid_deg")))
    elif entry["name"] == "tilt_wall":
        rows.append(("experiment, Santa-Cruz et al. (mean of three walls)", cf.get("experiment_deg")))
        rows.append(("the paper's model (Fig. 13)", cf.get("paper_model_deg")))
    return rows


def figure(entry, path: Path) -> Path | None:
    """Quantity against K_n (package points, Winkler curve for the toppling block, LMGC90's
    rigid value as the asymptote, closed forms) and |package - LMGC90| on log-log axes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    pk = [p for p in entry.get("package", []) if p.get("value") is not None]
    lm = _asymptote(entry)
    if not pk and lm is None:
        return None
    scale, unit = (1e3, "mm") if entry["quantity"] == "slide_m" else (1.0, "deg")
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=FIG_SIZE, dpi=FIG_DPI)
    kns = np.array([p["kn"] for p in pk])
    vals = np.array([p["value"] for p in pk])
    lo, hi = (kns.min() / 3, kns.max() * 30) if len(kns) else (cases.KN0 / 3, cases.KN0 * 30)
    if len(kns):
        ax.semilogx(kns, vals * scale, "o-", color="C0", label="this package (penalty law)")
    cfs = entry.get("closed_forms") or {}
    if cfs.get("winkler_params"):
        from drystone.mechanics import analytic
        xs = np.logspace(np.log10(lo), np.log10(hi), 25)
        b, h, t, rho = cfs["winkler_params"]
        ax.semilogx(xs, [analytic.toppling_tilt_deg(b, h, t, rho, x) for x in xs], "-", color="C0", alpha=0.4,
                    label=cfs.get("winkler_label", "Winkler closed form (penalty, static)"))
    if lm is not None:
        ax.axhline(lm * scale, color="C3", lw=2, label=f"LMGC90 (rigid), dt {entry['lmgc90'].get('dt_s'):g} s")
    styles = iter(["--", ":", "-."])
    for label, v in _closed_rows(entry):
        if v is not None:
            ax.axhline(v * scale, color="k", ls=next(styles, "--"), lw=1, label=label)
    ax.set_xlim(lo, hi)
    ax.set_xlabel("K_n (N/m^3)")
    ax.set_ylabel(f"{entry['quantity'].replace('_deg', '').replace('_m', '').replace('_', ' ')} ({unit})")
    ax.set_title(entry["title"], fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right" if entry["quantity"] == "collapse_angle_deg" else "best")
    if lm is not None and len(kns):
        d = np.abs(vals - lm) * scale
        ok = d > 0
        if ok.any():
            ax2.loglog(kns[ok], d[ok], "o-", color="C0", label="|package - LMGC90|")
            x0, y0 = kns[ok][0], d[ok][0]
            xs = np.array([x0, hi])
            ax2.loglog(xs, y0 * (xs / x0) ** (-1.0 / 3.0), "k:", lw=1, label="slope -1/3")
            ax2.loglog(xs, y0 * (xs / x0) ** (-0.5), "k--", lw=1, label="slope -1/2")
            ax2.loglog(xs, y0 * (xs / x0) ** (-1.0), "k-.", lw=1, label="slope -1")
        ax2.set_xlabel("K_n (N/m^3)")
        ax2.set_ylabel(f"difference to LMGC90 ({unit})")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=7)
    else:
        ax2.text(0.5, 0.5, "no package runs", ha="center", va="center", transform=ax2.transAxes)
        ax2.set_axis_off()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path)
    plt.close(fig)
    return path


def _case_section(k: str, entry: dict, figs: dict) -> list[str]:
    L = [f"## {entry['title']} (`{k}`)", ""]
    lm = entry.get("lmgc90") or {}
    if "error" in lm:
        L += [f"LMGC90 failed: `{lm['error'].splitlines()[0]}`", ""]
    rows = [("| engine / reference | K_n (N/m^3) | value | minus LMGC90 | time step (s) | cost |"),
            "|---|---|---|---|---|---|"]
    asym = _asymptote(entry)

    def diff(v):
        if v is None or asym is None:
            return "-"
        d = v - asym
        return f"{d * 1e3:+.3f} mm" if entry["quantity"] == "slide_m" else f"{d:+.3f} deg"

    if "value" in lm:
        rows.append(f"| LMGC90 {VERSION} (rigid, {lm.get('detection')}) | rigid | {_value_str(entry, lm['value'])} | 0 | "
                    f"{lm['dt_s']:g} | {lm['wall_s']:.1f} s ({lm['steps']} steps, {lm['ms_per_step']:.2f} ms/step) |")
    half = entry.get("lmgc90_half_dt")
    if half and "value" in half:
        rows.append(f"| LMGC90, half the step | rigid | {_value_str(entry, half['value'])} | {diff(half['value'])} | "
                    f"{half['dt_s']:g} | {half['wall_s']:.1f} s |")
    for label, v in _closed_rows(entry):
        rows.append(f"| {label} | - | {_value_str(entry, v)} | {diff(v)} | - | - |")
    wk = (entry.get("closed_forms") or {}).get("winkler_deg") or {}
    for p in entry.get("package", []):
        if "error" in p:
            rows.append(f"| this package | {p['kn']:.3g} | failed: {p['error'][:80]} | - | - | - |")
            continue
        rows.append(f"| this package (penalty law) | {p['kn']:.3g} | {_value_str(entry, p['value'])} | {diff(p['value'])} "
                    f"| {p['dt_s']:.3g} | {p['wall_s']:.1f} s |")
        w = wk.get(f"{p['kn']:g}")
        if w is not None:
            label = (entry.get("closed_forms") or {}).get("winkler_label", "Winkler closed form (package's law, static)")
            rows.append(f"| {label} | {p['kn']:.3g} | {_value_str(entry, w)} | {diff(w)} | - | - |")
    L += rows + [""]
    pk = [p for p in entry.get("package", []) if p.get("value") is not None]
    slope = study.deficit_slope([p["kn"] for p in pk], [p["value"] for p in pk], asym)
    if slope is not None:
        L += [f"Convergence: |package - LMGC90| ~ K_n^{slope:.2f} over the K_n above (least squares on log-log).", ""]
    if lm.get("collapse"):
        c = lm["collapse"]
        L += [f"LMGC90 collapse: detected at {_f(c.get('detected_angle_deg'), 3)} deg ({c.get('criterion')}), "
              f"reaction-drop angle {_f(c.get('reaction_drop_angle_deg'), 3)} deg, onset block {c.get('onset_block')}.", ""]
    if k in figs:
        L += [f"![{k}]({figs[k].name})", ""]
    return L


def _tilt_walls_summary(entries: dict) -> list[str]:
    """One row per Santa-Cruz wall run: LMGC90's rigid collapse angle beside the package's
    at each K_n, the experiment and the paper's model (all in degrees of tilt)."""
    walls = {k: e for k, e in entries.items() if e.get("name") == "tilt_wall"}
    if not walls:
        return []
    kns = sorted({p["kn"] for e in walls.values() for p in e.get("package", []) if p.get("value") is not None})
    L = ["## Santa-Cruz tilt walls: summary", "",
         "Collapse angle (deg of tilt), each engine's onset read with the package's rule; the experiment is the "
         "mean of three walls, the paper's model its Fig. 13 value; the walls are generated (ASSUMED layout).", "",
         "| wall (seed) | LMGC90 (rigid) | " + " | ".join(f"package K_n {k:.0e}" for k in kns) + " |",
         "|---|---|" + "---|" * len(kns)]
    for k, e in sorted(walls.items(), key=lambda kv: (kv[1].get("variant") is None, kv[1].get("variant") or 0)):
        lm = (e.get("lmgc90") or {}).get("value")
        by_kn = {p["kn"]: p.get("value") for p in e.get("package", [])}
        L.append(f"| {e.get('variant')} | {_f(lm, 2)} | " + " | ".join(_f(by_kn.get(x), 2) for x in kns) + " |")
    cf = next((e.get("closed_forms") for e in walls.values() if e.get("closed_forms")), {}) or {}
    if cf:
        L += ["", f"Experiment {_f(cf.get('experiment_deg'), 2)} ± {_f(cf.get('experiment_sd_deg'), 2)} deg; "
                  f"the paper's model {_f(cf.get('paper_model_deg'), 2)} deg."]
    return L + [""]


def write(out: Path = study.OUT) -> Path:
    data = study.load(out)
    out = Path(out)
    figs = {}
    for k, entry in data["cases"].items():
        p = figure(entry, out / f"convergence_{k}.png")
        if p is not None:
            figs[k] = p
    L = ["# Cross-check with LMGC90 (rigid contacts)", "",
         "_Generated by `python -m drystone.studies.crosscheck report` from `crosscheck.json`._", "",
         f"LMGC90 through `compas_lmgc90` {VERSION} (non-smooth contact dynamics: rigid blocks, Signorini "
         "condition, Coulomb friction, restitution 0) runs the same case as this package (same block file or "
         "generator, same materials, same stages: `drystone/studies/crosscheck/lmgc90.py` resolves the case with "
         "`drystone.model.resolve`). This package runs it at K_n = 2e8 N/m^3 (the papers' value) and stiffer; as K_n "
         "grows its results must approach LMGC90's.", "",
         "## Assumptions", ""] + [f"* {a}" for a in ASSUMED] + [
         "* Translation (`drystone/studies/crosscheck/translate.py`): every block is the convex hull of its vertices, given "
         "to LMGC90 as a rigid polyhedron (each hull face fanned into outward triangles, reference point at the "
         "volume centroid, the material's density); platform and fixed blocks have all six velocities imposed; one "
         f"contact law ({translate.LAW}) for all contacts, alert distance {translate.ALERT_M:g} m.", "",
         f"Engine: `{engine.__name__}` in its own process per run; LMGC90 module variables used: "
         "`__bulk_behaviour_MOD_grav1..3`, `__prprx_MOD_sto_set_explicit_detection_prprx`.", ""]
    if not data["cases"]:
        L += ["No case has been run yet: `python -m drystone.studies.crosscheck small` (or `all`).", ""]
    L += _tilt_walls_summary(data["cases"])
    for k, entry in data["cases"].items():
        L += _case_section(k, entry, figs)
    out.mkdir(parents=True, exist_ok=True)
    return markdown.write(out / "report.md", "\n".join(L) + "\n")  # and report.html beside it
