"""What stone shape does to a wall's collapse: tilt collapse angle and PGA at collapse of
walls of one footprint, height and weight built of coursed, polygonal convex, polygonal
interlocking (multi-part) and split interlocking stones (plan.py), by the package's
analyses (drystone/analyses/: ``tilt`` and ``collapse``).

Steps (``python -m drystone.studies.shape``):

1. ``plan``: geometries and record windows (plan.py);
2. ``run``: per wall (variant and seed), the ``tilt`` analysis of cases/shape/tilt.toml with
   the wall's geometry (its protocol, drystone/studies/common.py ``tilt_protocol``) and the ``collapse``
   analysis of cases/shape/record.toml with the wall's geometry under the records' windows,
   its search set to the study's grid (common.py ``search_params``: the first run at half the
   cap, then the middles of the bracket down to ``resolution_g``, censored at the cap), into
   ``results/<out>/walls/<variant>_s<seed>/{tilt,collapse}/``; several walls at once (each
   analysis resumable: finished runs with the same fingerprint are reused, local process
   pool or Dask). A variant the package refuses (a CaseError before any run) is left out and
   reported with the refusal;
3. ``report``: the analyses' JSON read back (``collect``), the statistics and tests
   (``compare``), ``shape.json``, ``runs.csv``, ``shape.png`` and ``report.md``.

Collapse of a seismic run: the package's one criterion (drystone/analyses/common.py
``outcome``: a stone fell, overturned or left the model), at the end of the run (the record,
then a rest of at most the case's 2.5 s). Before the study ran on the analyses it read
collapse as the Sacsayhuaman paper does (studies/sacsayhuaman/analysis.py ``residuals``:
a centroid out of plane by more than half the stone's depth, or down by more than its
height, or off the model) and bisected its own grid; docs/beyond-the-papers.md says which
numbers came from which. Collapse angle of a tilt run: the tilt analysis's headline (the
onset, as the tilt study), with the reaction-drop angle beside it.
"""
from __future__ import annotations

import csv
import itertools
import json
import os
import time
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.postprocess import markdown
from drystone.studies import common as sc
from drystone.studies.shape import plan as planmod

#: two variants differ "beyond the seed-to-seed spread" when an exact two-sided permutation
#: test of their mean (over every split of the pooled seeds) gives p <= this; with 3 seeds
#: each the smallest p possible is 2 / C(6, 3) = 0.1 (the two sets do not overlap at all)
ALPHA = 0.1
CSV_FIELDS = ("kind", "variant", "seed", "record", "pga_g", "name", "status", "collapsed", "collapsed_stones",
              "settled", "collapse_angle_deg", "reaction_drop_angle_deg", "simulated_s", "wall_s", "error")


# --- runs -------------------------------------------------------------------------------------------------
def searches(cfg, variants=None) -> list[tuple[str, int, str]]:
    cfg = planmod.get(cfg)
    return [(v, s, r) for v in (cfg.variants if variants is None else variants) for s in cfg.seeds
            for r in cfg.records]


def walls(cfg, variants=None) -> list[tuple[str, int]]:
    cfg = planmod.get(cfg)
    return [(v, s) for v in (cfg.variants if variants is None else variants) for s in cfg.seeds]


def tilt_wall(cfg, variant: str, seed: int, workers=1, backend="local", address=None, log=print) -> dict:
    """The tilt analysis of one wall (tilt.json's dict)."""
    from drystone.analyses import tilt

    cfg = planmod.get(cfg)
    return tilt.tilt(planmod.TILT_CASE, out=planmod.wall_dir(cfg, variant, seed) / "tilt", workers=workers,
                     backend=backend, address=address, log=log,
                     overrides=sc.quick_gravity(cfg.quick) + planmod.wall_overrides(cfg, variant, seed),
                     **sc.tilt_protocol(planmod.TILT_CASE, cfg.quick))


def collapse_wall(cfg, plan: dict, variant: str, seed: int, workers=None, backend="local", address=None,
                  log=print) -> dict:
    """The collapse analysis of one wall under the records' windows (collapse.json's dict)."""
    from drystone.analyses import collapse

    cfg = planmod.get(cfg)
    files = [plan["records"][r]["file"] for r in cfg.records]
    return collapse.collapse(planmod.RECORD_CASE, files, out=planmod.wall_dir(cfg, variant, seed) / "collapse",
                             workers=workers or len(files), backend=backend, address=address,
                             overrides=planmod.common_overrides(cfg) + planmod.wall_overrides(cfg, variant, seed),
                             log=log, **sc.search_params(cfg.pga_cap_g, cfg.resolution_g),
                             stop_when_fallen=False)  # runs to their end: the published runs


def _duration(cfg, plan: dict, record: str) -> float:
    d = plan["records"][record]["duration_s"]
    return min(d, cfg.record_duration_s) if cfg.record_duration_s else d


def _refusal(cfg, plan: dict, variant: str, exc: Exception) -> str:
    """A refusal of a variant with multi-part stones (before any run), as text; a refusal of
    one without is a fault of the study, raised."""
    if not any(g["multi_part"] for g in plan["geometries"].values() if g["variant"] == variant):
        raise exc
    return str(exc)


def _log(m: str) -> None:
    print(m, flush=True)


def wall_task(cfg, plan: dict, variant: str, seed: int, each: int, backend="local", address=None) -> dict:
    """One wall's tilt and collapse analyses; returns {"failed": [runs], "refused": text or
    None} (a module-level function: ``drystone.studies.in_parallel`` runs several at once)."""
    from drystone.model.case import CaseError

    failed = []
    try:
        if cfg.tilt:
            t = tilt_wall(cfg, variant, seed, 1, backend, address, _log)
            failed += [f"{variant}_s{seed}/tilt/{d['run']}" for d in t["directions"].values()
                       if d.get("status") == "failed"]
        c = collapse_wall(cfg, plan, variant, seed, each, backend, address, _log)
        failed += [f"{variant}_s{seed}/collapse/runs/{x['name']}" for r in c["records"].values() for x in r["runs"]
                   if x.get("status") != "done"]
    except CaseError as exc:
        return {"failed": failed, "refused": _refusal(cfg, plan, variant, exc)}
    return {"failed": failed, "refused": None}


def run(config="full", workers=None, backend="local", address=None) -> dict:
    """Plan, then per wall its tilt and collapse analyses, several walls at once (module
    docstring). Returns {"rounds", "runs_run", "runs_reused", "interrupted", "refused",
    "failed", "elapsed_s"}."""
    from drystone.studies import in_parallel

    cfg = planmod.get(config)
    t0 = time.time()
    load0 = sc.load_average()
    plan = planmod.build(cfg)
    cores = workers or os.cpu_count() or 1
    each = min(cores, len(cfg.records))  # one collapse analysis runs its records' searches at once
    refused, failed = {}, []
    summary = {"rounds": 0, "runs_run": 0, "runs_reused": 0, "interrupted": False, "refused": refused,
               "failed": failed, "workers": workers, "backend": backend, "cores": os.cpu_count(),
               "load_average_start": load0}
    try:
        for (v, _), res in zip(walls(cfg), in_parallel(wall_task, [(cfg, plan, v, s, each, backend, address)
                                                                   for v, s in walls(cfg)], max(1, cores // each))):
            failed += res["failed"]
            if res["refused"]:
                refused.setdefault(v, res["refused"])
    except KeyboardInterrupt:
        summary["interrupted"] = True
    atomic.write_text(cfg.out_dir / "refused.json", json.dumps(refused, indent=1) + "\n")
    for v, why in refused.items():
        print(f"[shape] variant {v} left out: {why}", flush=True)
    folders = [planmod.wall_dir(cfg, v, s) / k for v, s in walls(cfg) for k in ("tilt", "collapse")]
    summary["runs_run"], summary["runs_reused"], summary["rounds"] = sc.count_runs(folders, t0)
    return sc.finish(cfg.out_dir, summary, t0)


# --- collect and compare ----------------------------------------------------------------------------------
def collect(config="full") -> dict:
    """Every search and tilt of the walls' analyses on disk (collapse.json, tilt.json)."""
    cfg = planmod.get(config)
    plan = planmod.load_plan(cfg)
    refused = sc.read_json(cfg.out_dir / "refused.json") or {}
    out = {"searches": [], "tilt": []}
    for v, s, r in searches(cfg):
        key = {"variant": v, "seed": s, "record": r}
        if v in refused:
            out["searches"].append(dict(key, status="refused", runs=[], bracket=None, error=refused[v]))
            continue
        d = planmod.wall_dir(cfg, v, s) / "collapse"
        res = sc.read_json(d / "collapse.json") or {"records": {}}
        stem = Path(plan["records"][r]["file"]).stem
        out["searches"].append(sc.search_state(key, res["records"].get(stem), d))
    if cfg.tilt:
        for v, s in walls(cfg):
            key = {"variant": v, "seed": s, "name": f"{v}-s{s}"}
            if v in refused:
                out["tilt"].append(dict(key, status="refused", error=refused[v]))
                continue
            d = planmod.wall_dir(cfg, v, s) / "tilt"
            res = sc.read_json(d / "tilt.json") or {"directions": {}}
            out["tilt"].append(sc.tilt_row(key, next(iter(res["directions"].values()), None), d))
    out["plan"] = plan
    return out


def permutation_p(a, b) -> float | None:
    """Exact two-sided permutation p-value of the difference of means of ``a`` and ``b``
    (every split of the pooled values into groups of their sizes; ties count as extreme)."""
    a, b = [float(x) for x in a], [float(x) for x in b]
    if len(a) < 2 or len(b) < 2:
        return None
    pool = a + b
    obs = abs(np.mean(a) - np.mean(b))
    n, hits, total = len(a), 0, 0
    for idx in itertools.combinations(range(len(pool)), n):
        s = set(idx)
        x = [pool[i] for i in idx]
        y = [pool[i] for i in range(len(pool)) if i not in s]
        total += 1
        hits += abs(np.mean(x) - np.mean(y)) >= obs - 1e-12 * max(1.0, obs)
    return hits / total


def describe(values) -> dict:
    v = np.asarray([x for x in values if x is not None], float)
    if not len(v):
        return {"n": 0}
    return {"n": int(len(v)), "mean": float(v.mean()), "sd": float(v.std(ddof=1)) if len(v) > 1 else None,
            "min": float(v.min()), "max": float(v.max()), "values": v.tolist()}


def measures(data: dict, cfg) -> dict:
    """Per measure (tilt onset, tilt reaction drop, collapse PGA per record and over the
    records) and variant: the per-seed values and their statistics. A censored search
    (standing at the cap) counts as the cap + one step, and is flagged."""
    cfg = planmod.get(cfg)
    out = {}
    for key, label in (("collapse_angle_deg", "tilt collapse angle, onset (deg)"),
                       ("reaction_drop_angle_deg", "tilt collapse angle, reaction drop (deg)")):
        out[key] = {"label": label, "variants": {}}
        for v in cfg.variants:
            rows = [r for r in data["tilt"] if r["variant"] == v and r.get("status") == "done"]
            vals = {r["seed"]: r.get(key) for r in rows}
            out[key]["variants"][v] = {"seeds": vals, **describe(vals.values())}
    for rec in list(cfg.records) + (["mean over records"] if len(cfg.records) > 1 else []):
        key = f"pga_{rec}" if rec != "mean over records" else "pga_mean"
        out[key] = {"label": f"PGA at collapse, {rec} (g)", "variants": {}}
        for v in cfg.variants:
            vals, cens = {}, []
            for s in cfg.seeds:
                recs = cfg.records if rec == "mean over records" else (rec,)
                ests = []
                for r in recs:
                    st = next((x for x in data["searches"] if (x["variant"], x["seed"], x["record"]) == (v, s, r)), None)
                    if not st or st["status"] != "done":
                        ests = None
                        break
                    b = st["bracket"]
                    if b["censored"]:
                        cens.append((s, r))
                        ests.append(cfg.pga_cap_g + cfg.resolution_g)
                    else:
                        ests.append(b["estimate_g"])
                if ests:
                    vals[s] = float(np.mean(ests))
            out[key]["variants"][v] = {"seeds": vals, "censored": cens, **describe(vals.values())}
    return out


#: variants built on one seed's polygonal layout (their seeds pair: same face cells)
SAME_LAYOUT = ("polygonal", "interlocking", "interlocking_split")
PAIRS = (("coursed", "polygonal", "coursed vs polygonal convex: (a) vs (b)"),
         ("polygonal", "interlocking", "convex vs interlocking: (b) vs (c)"),
         ("polygonal", "interlocking_split", "convex vs split interlocking: (b) vs (c')"),
         ("coursed", "interlocking", "coursed vs interlocking: (a) vs (c)"),
         ("coursed", "interlocking_split", "coursed vs split interlocking: (a) vs (c')"),
         ("interlocking", "interlocking_split", "one body vs split: (c) vs (c')"))


def compare(ms: dict, cfg) -> dict:
    """Per measure and pair of variants: the difference of means, the seed-to-seed spread
    (the larger standard deviation), and the exact permutation test (``ALPHA``)."""
    cfg = planmod.get(cfg)
    out = {}
    for key, m in ms.items():
        n_rec = len(cfg.records) if key == "pga_mean" else 1  # censored searches per seed at most
        rows = []
        for a, b, label in PAIRS:
            if a not in cfg.variants or b not in cfg.variants:
                continue
            va, vb = m["variants"][a], m["variants"][b]
            row = {"a": a, "b": b, "label": label}
            if va["n"] and vb["n"]:
                sds = [x for x in (va.get("sd"), vb.get("sd")) if x is not None]
                p = permutation_p(va["values"], vb["values"])
                row.update(difference=vb["mean"] - va["mean"], spread=max(sds) if sds else None, p=p,
                           beyond=None if p is None else bool(p <= ALPHA),
                           overlap=bool(max(va["min"], vb["min"]) <= min(va["max"], vb["max"])),
                           censored={a: len(va.get("censored") or []), b: len(vb.get("censored") or [])},
                           both_censored=bool(len(va.get("censored") or []) == va["n"] * n_rec
                                              and len(vb.get("censored") or []) == vb["n"] * n_rec))
                if a in SAME_LAYOUT and b in SAME_LAYOUT:  # one seed, one face layout: differences per seed
                    common = [k for k in va["seeds"] if k in vb["seeds"] and va["seeds"][k] is not None
                              and vb["seeds"][k] is not None]
                    row["paired"] = {k: vb["seeds"][k] - va["seeds"][k] for k in common}
            rows.append(row)
        out[key] = rows
    return out


# --- outputs ----------------------------------------------------------------------------------------------
def write_csv(data: dict, path: Path) -> Path:
    with atomic.aside(path) as _tmp, open(_tmp, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in data["tilt"]:
            w.writerow({"kind": "tilt", **{k: ("" if r.get(k) is None else r.get(k)) for k in CSV_FIELDS if k != "kind"}})
        for st in data["searches"]:
            for r in st["runs"]:
                row = {"kind": "seismic", "variant": st["variant"], "seed": st["seed"], "record": st["record"], **r}
                row["collapsed_stones"] = " ".join(map(str, r.get("collapsed_stones") or []))
                w.writerow({k: ("" if row.get(k) is None else row.get(k)) for k in CSV_FIELDS})
    return path


COLOURS = {"coursed": "tab:blue", "polygonal": "tab:orange", "interlocking": "tab:green",
           "interlocking_split": "tab:red"}


def figure(data: dict, ms: dict, cfg, path: Path) -> Path:
    """Left: tilt collapse angle (onset) per variant, one dot per seed, mean and +-1 sd.
    Then one panel per record: the PGA bracket of every seed (a bar from the highest PGA
    standing to the lowest collapsing; an arrow above the cap when the wall stood)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cfg = planmod.get(cfg)
    n = len(cfg.records) + (1 if cfg.tilt else 0)
    fig, axes = plt.subplots(1, n, figsize=(3.3 * n + 0.5, 4.2))
    axes = list(np.atleast_1d(axes))
    xs = {v: k for k, v in enumerate(cfg.variants)}
    labels = [planmod.VARIANTS[v][0] for v in cfg.variants]
    if cfg.tilt:
        ax = axes.pop(0)
        for v in cfg.variants:
            for key, mk in (("collapse_angle_deg", "o"), ("reaction_drop_angle_deg", "^")):
                m = ms[key]["variants"][v]
                vals = list(m["seeds"].values())
                jitter = np.linspace(-0.12, 0.12, max(1, len(vals)))
                off = -0.18 if mk == "o" else 0.18
                ax.scatter(xs[v] + off + jitter[:len(vals)], [x if x is not None else np.nan for x in vals],
                           marker=mk, color=COLOURS.get(v, "k"), s=22, zorder=3)
                if m["n"]:
                    ax.errorbar(xs[v] + off, m["mean"], yerr=m.get("sd") or 0, color="k", capsize=4, lw=1,
                                marker="_", ms=14, zorder=4)
        ax.set_xticks(range(len(cfg.variants)), labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylabel("platform tilt at collapse (deg)")
        ax.set_title("tilt: onset (o), reaction drop (^)", fontsize=9)
        ax.grid(alpha=0.3)
    for ax, rec in zip(axes, cfg.records):
        for v in cfg.variants:
            sts = [x for x in data["searches"] if x["variant"] == v and x["record"] == rec]
            for j, st in enumerate(sts):
                x = xs[v] + (j - (len(sts) - 1) / 2) * 0.15
                b = st.get("bracket")
                if st["status"] != "done" or not b:
                    ax.text(x, 0.05, "·" if st["status"] == "pending" else "x", ha="center", fontsize=8)
                    continue
                if b["censored"]:
                    ax.annotate("", xy=(x, cfg.pga_cap_g + 0.35), xytext=(x, cfg.pga_cap_g),
                                arrowprops={"arrowstyle": "->", "color": COLOURS.get(v, "k")})
                else:
                    ax.plot([x, x], [b["low_g"], b["high_g"]], color=COLOURS.get(v, "k"), lw=4, solid_capstyle="butt")
            m = ms[f"pga_{rec}"]["variants"][v]
            if m["n"]:  # dashed: censored seeds counted at the cap + one step (a lower bound)
                ax.plot([xs[v] - 0.3, xs[v] + 0.3], [m["mean"]] * 2, color="k", lw=1,
                        ls="--" if m.get("censored") else "-")
        ax.axhline(cfg.pga_cap_g, color="0.6", ls=":", lw=1)
        ax.set_xticks(range(len(cfg.variants)), labels, rotation=30, ha="right", fontsize=8)
        ax.set_ylim(0, cfg.pga_cap_g + 0.45)
        ax.set_ylabel("PGA at collapse (g)")
        ax.set_title(f"{rec}: bracket per seed, mean (-);\n↑ stood at the cap", fontsize=9)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def _f(x, spec=".2f", none="-"):
    return none if x is None else format(x, spec)


def _cell(m: dict, spec=".2f") -> str:
    if not m["n"]:
        return "not run"
    s = f"{m['mean']:{spec}}"
    if m.get("sd") is not None:
        s += f" ± {m['sd']:{spec}}"
    s += f" ({m['min']:{spec}}-{m['max']:{spec}}, n = {m['n']})"
    if m.get("censored"):
        s += f", {len(m['censored'])} censored"
    return s


def costs(data: dict) -> dict:
    runs = [r for st in data["searches"] for r in st["runs"] if r.get("status") == "done"]
    tilt = [r for r in data["tilt"] if r.get("status") == "done"]
    out = {}
    for key, rows in (("seismic", runs), ("tilt", tilt)):
        w = [r["wall_s"] for r in rows if r.get("wall_s")]
        sim = [r["simulated_s"] for r in rows if r.get("simulated_s")]
        out[key] = {"runs": len(rows), "core_s": float(sum(w)), "mean_wall_s": float(np.mean(w)) if w else None,
                    "max_wall_s": float(max(w)) if w else None, "simulated_s": float(sum(sim)),
                    "wall_per_simulated_s": float(sum(w) / sum(sim)) if sim and w else None}
    return out


SHAPE_PAIRS = (("coursed", "polygonal"), ("polygonal", "interlocking"), ("coursed", "interlocking"))


def answer(cmp: dict, cfg) -> list[str]:
    """The study's answers, one line per measure, from the tests (``compare``): does shape
    change it beyond the seed-to-seed spread (any of (a)-(b), (b)-(c), (a)-(c)), is (c)
    against (c') beyond it, and does the first answer change with (c') in place of (c)?"""
    cfg = planmod.get(cfg)
    keys = ([k for k in ("collapse_angle_deg",) if cfg.tilt] + [f"pga_{r}" for r in cfg.records]
            + (["pga_mean"] if len(cfg.records) > 1 else []))
    names = {"collapse_angle_deg": "Tilt collapse angle (onset)", "pga_mean": "PGA at collapse, mean over the records",
             **{f"pga_{r}": f"PGA at collapse under {r}" for r in cfg.records}}
    lines = []
    for k in keys:
        unit = "deg" if k.startswith("collapse") else "g"
        rows = {(r["a"], r["b"]): r for r in cmp.get(k, []) if r.get("p") is not None}

        def verdict(pairs):
            got = [rows[p] for p in pairs if p in rows]
            return (any(r["beyond"] for r in got) if got else None), [r for r in got if r["beyond"]]

        def say(r):
            cens = [planmod.VARIANTS[v][0].split()[0] for v, n in (r.get("censored") or {}).items() if n]
            return (f"{r['label']} {r['difference']:+.2f} {unit} (larger seed sd {_f(r['spread'])}, "
                    f"p = {r['p']:.2f}" + (f"; {' and '.join(cens)} stood at the cap in some seeds, counted at the "
                                           "cap + one step: a bound" if cens else "") + ")")

        shape, which = verdict(SHAPE_PAIRS)
        if shape is None:
            lines.append(f"* **{names[k]}**: not enough finished seeds to compare.")
            continue
        text = (f"* **{names[k]}**: shape changes it beyond the seed-to-seed spread: **{'yes' if shape else 'no'}**"
                + (" (" + "; ".join(say(r) for r in which) + ")" if which else ""))
        one = rows.get(("interlocking", "interlocking_split"))
        if one is not None and one.get("both_censored"):
            text += ". Splitting the stones: (c) and (c') both stood at the cap in every seed: no difference measurable"
        elif one is not None:
            split_pairs = [(a, "interlocking_split" if b == "interlocking" else b) for a, b in SHAPE_PAIRS]
            shape_split, _ = verdict(split_pairs)
            pd = list((one.get("paired") or {}).values())
            same = (f"; per seed (same layout) {', '.join(f'{d:+.2f}' for d in pd)}"
                    + (", all of one sign" if pd and (all(d > 0 for d in pd) or all(d < 0 for d in pd)) else "")
                    if pd else "")
            text += (f". Splitting the stones: (c') - (c) = {one['difference']:+.2f} {unit}, p = {one['p']:.2f}: "
                     f"**{'beyond' if one['beyond'] else 'within'}** the spread{same}; with (c') in place of (c) the "
                     f"answer is {'yes' if shape_split else 'no'} ("
                     + ("the same" if shape_split == shape else "**it changes**") + ")")
        lines.append(text + ".")
    return lines


def report(config="full") -> Path:
    cfg = planmod.get(config)
    data = collect(cfg)
    plan = data["plan"]
    ms = measures(data, cfg)
    cmp = compare(ms, cfg)
    c = costs(data)
    timing = sc.read_json(cfg.out_dir / "timing.json") or []
    refused = sc.read_json(cfg.out_dir / "refused.json") or {}
    fig = figure(data, ms, cfg, cfg.out_dir / "shape.png")
    write_csv(data, cfg.out_dir / "runs.csv")
    status = {s: sum(st["status"] == s for st in data["searches"]) for s in ("done", "pending", "failed", "refused")}
    atomic.write_text(cfg.out_dir / "shape.json", json.dumps(
        {"config": plan["config"], "searches": data["searches"], "tilt": data["tilt"], "measures": ms,
         "comparisons": cmp, "cost": c, "timing": timing, "refused": refused, "status": status},
        indent=1, default=str) + "\n")
    fp = plan["footprint"]
    L = [f"# What stone shape does to collapse (config `{cfg.name}`)", ""]
    if cfg.notes:
        L += [f"**Note: {'; '.join(cfg.notes)}.**", ""]
    if status["pending"] or status["failed"] or status["refused"]:
        L += [f"**Incomplete: {status['done']} of {len(data['searches'])} searches done, {status['pending']} pending, "
              f"{status['failed']} failed, {status['refused']} refused (see below).**", ""]
    L += ["## Walls", "",
          f"{len(cfg.variants)} walls of the Sacsayhuaman section's footprint {fp['length']:g} m x {fp['thickness']:g} m, height "
          f"{fp['height']:g} m and density {fp['material']['density']:g} kg/m³ (Table 1, FEM column: K_n "
          f"{fp['material']['kn']:.3g}, K_t {fp['material']['kt']:.3g} N/m³, μ {fp['material']['mu']:g}, damping "
          f"{fp['material']['damping']:g}), every stone through the full thickness, on a rigid platform; stones on the "
          "platform fixed, free stones at the wall's ends held as the section's side blocks (blocked_dofs "
          f"\"{planmod.END_DOFS}\": out of plane, up and rotation out of plane only; drystone/studies/shape/plan.py). "
          f"Polygonal walls: `polygonal_wall`, typology \"sacsayhuaman\", stone sizes {list(planmod.STONE_SIZE)} m "
          f"(equivalent diameters), {planmod.LLOYD} Lloyd steps; (c) merges pairs of (b)'s cells into re-entrant "
          f"stones (reentrant = {planmod.REENTRANT:g}), (c') cuts them back into their convex parts, each its own "
          "block. Generated outlines, not surveyed ones (ASSUMED, as the section's own).", "",
          "| variant | seed | stones | multi-part stones (parts) | fixed | held at the ends | weight (N) | "
          "free stones' weight (N) |", "|---|---|---|---|---|---|---|---|"]
    for k, g in plan["geometries"].items():
        L.append(f"| {planmod.VARIANTS[g['variant']][0]} | {g['seed']} | {g['stones']} | {g['multi_part']} "
                 f"({g['parts']}) | {g['fixed']} | {g['held_ends']} | {g['weight_N']:.1f} | {g['free_weight_N']:.0f} |")
    ws = [g["weight_N"] for g in plan["geometries"].values()]
    L += ["", f"Weights agree within {(max(ws) - min(ws)) / max(ws):.1e} (relative; the study requires "
              f"{planmod.WEIGHT_REL_TOL:g}): every wall tiles the same face through the same thickness at one density.",
          ""]
    if refused:
        L += ["Variants not run (the package refused them before YADE): "
              + "; ".join(f"**{v}**: {why}" for v, why in refused.items()) + ".", ""]
    L += ["## Records (ASSUMED stand-ins)", "",
          "| record | source | stands for | window run (s of the record) | duration run (s) | of full (s) | "
          "share of its Arias intensity | PGA (g) |", "|---|---|---|---|---|---|---|---|"]
    for name in cfg.records:
        r = plan["records"][name]
        fema = r.get("fema")
        src = (f"FEMA P695 {fema['fema_set']} record {fema['fema_record_id']}{fema['fema_component']}: {r['event']}, "
               f"{r['station']} {r['component']} (ASSUMED analogue)" if fema else f"user file: {r['event']}")
        L.append(f"| {name} | {src} | {r.get('stands_for') or '-'} | {r['window_s'][0]:.2f}-{r['window_s'][1]:.2f} | "
                 f"{_duration(cfg, plan, name):.2f} | {r['full_duration_s']:.2f} | {100 * r['arias_share']:.0f} % "
                 f"(core) | {r['pga_g']:.3f}{'' if r['pga_inside'] else ' (not in the window!)'} |")
    capped = [n for n in cfg.records if plan["records"][n].get("core_capped_to_s")]
    L += ["", "**Records shortened** to keep the study's cost down: each is cut to its strong-motion window, 5-95 % "
              f"of its Arias intensity (the core) ± {planmod.PAD_S:g} s Hann-tapered pads"
          + (f"; where the core would be longer than {planmod.MAX_CORE_S:g} s ({', '.join(capped)}) it is the "
             f"{planmod.MAX_CORE_S:g} s holding the most Arias intensity" if capped else "")
          + ". The record's PGA lies inside every window. Applied out of plane (y), scaled to each PGA, then a rest of "
          "at most 2.5 s (cases/shape/record.toml)"
          + (f"; here further cut to {cfg.record_duration_s:g} s and a {cfg.rest_max_s:g} s rest"
             if cfg.record_duration_s else "") + ". The records are the Sacsayhuaman study's catalogue "
          "(drystone/motions/catalogue.py): FEMA P695 far-field analogues unless your files are in "
          "data/records/user/.", "",
          "## Method", "",
          "* Tilt: the `tilt` analysis with cases/shape/tilt.toml's protocol (gravity, 2 deg/s to 5 deg, then 1 deg/s "
          "out of plane until collapse)"
          + (f"; here gravity held {sc.QUICK_GRAVITY['duration']:g} s, {sc.QUICK_TILT['lead_rate']:g} then "
             f"{sc.QUICK_TILT['rate']:g} deg/s (every run's gravity shortened alike)" if cfg.quick else "")
          + ": the collapse angle as the tilt study measures it (onset of the motion that led to collapse, "
          "drystone/mechanics/collapse.py), the reaction-drop angle beside it.",
          f"* PGA at collapse: the `collapse` analysis (drystone/analyses/collapse.py), its search set to a "
          f"{cfg.resolution_g:g} g grid: the first run at {cfg.pga_cap_g / 2:g} g, the cap {cfg.pga_cap_g:g} g next "
          "when the wall stood there, then the middle of the bracket until it is "
          f"{cfg.resolution_g:g} g wide (0 g, gravity alone, assumed standing), each step a run; collapse = the "
          "package's one criterion (a stone fell, overturned or left the model: drystone/analyses/common.py "
          "`outcome`). Result: the bracket (highest PGA standing, lowest collapsing]; its middle is the estimate. A "
          "wall standing at the cap is censored (counted "
          f"as {cfg.pga_cap_g + cfg.resolution_g:g} g in the means and flagged). ASSUMED: collapse is monotonic in "
          "PGA (one record scaled up); a standing run above a collapsing one is flagged in shape.json.",
          f"* Beyond the seed-to-seed spread: the exact two-sided permutation test of the difference of the "
          f"variants' means over the seeds (every split of the pooled seeds), p <= {ALPHA:g}. With 3 seeds each, "
          "p = 0.1 is the smallest possible: the two sets of seeds do not overlap at all. (b), (c) and (c') of one "
          "seed share the face layout, so their per-seed differences are listed too (with 3 seeds a paired "
          "sign test cannot reach p <= 0.1: 2 / 2^3 = 0.25 at best; read them as consistency).", "",
          "## Results", "",
          "Mean ± seed-to-seed standard deviation (range, seeds):", "",
          "| measure | " + " | ".join(planmod.VARIANTS[v][0] for v in cfg.variants) + " |",
          "|---|" + "---|" * len(cfg.variants)]
    for key, m in ms.items():
        if key.startswith("collapse") or key.startswith("reaction"):
            if not cfg.tilt:
                continue
        L.append(f"| {m['label']} | " + " | ".join(_cell(m["variants"][v]) for v in cfg.variants) + " |")
    L += ["", "**Answer.**", ""] + answer(cmp, cfg) + ["", f"![shape study]({fig.name})", "",
                                                        "## Comparisons", "",
                                                        "| measure | pair | difference of means (b - a) | larger "
                                                        "seed sd | ranges overlap | p | beyond the spread | "
                                                        "per seed, same layout (b - a) |",
                                                        "|---|---|---|---|---|---|---|---|"]
    for key, rows in cmp.items():
        if key == "reaction_drop_angle_deg" or (key.startswith("collapse") and not cfg.tilt):
            continue
        for r in rows:
            if r.get("p") is None and "difference" not in r:
                L.append(f"| {ms[key]['label']} | {r['label']} | - | - | - | - | - | - |")
                continue
            paired = ", ".join(f"{d:+.2f}" for d in r["paired"].values()) if r.get("paired") else "-"
            L.append(f"| {ms[key]['label']} | {r['label']} | {r['difference']:+.2f} | {_f(r['spread'])} | "
                     f"{'yes' if r['overlap'] else 'no'} | {_f(r['p'])} | "
                     f"{'-' if r['beyond'] is None else ('yes' if r['beyond'] else 'no')} | {paired} |")
    L += ["", "## Every search", "",
          "| variant | seed | record | bracket (g) | runs (PGA: c = collapse, s = standing) |", "|---|---|---|---|---|"]
    for st in data["searches"]:
        b = st.get("bracket")
        br = ("refused" if st["status"] == "refused" else
              f"> {b['low_g']:g} (stood at the cap)" if b and b["censored"] else
              f"({b['low_g']:g}, {b['high_g']:g}]" if b and b["done"] else sc.missing_text(st["status"]))
        seq = ", ".join(f"{r['pga_g']:g}: {'c' if r.get('collapsed') else 's' if r.get('status') == 'done' else r['status']}"
                        for r in st["runs"])
        L.append(f"| {planmod.VARIANTS[st['variant']][0]} | {st['seed']} | {st['record']} | {br} | {seq} |")
    odd = [f"{planmod.VARIANTS[st['variant']][0]} seed {st['seed']} {st['record']}: stood at "
           + ", ".join(f"{p:g}" for p in st["bracket"]["non_monotonic"]) + " g"
           for st in data["searches"] if st.get("bracket") and st["bracket"].get("non_monotonic")]
    L += ["", "Non-monotonic searches (a wall standing above a PGA that collapsed it): "
          + ("; ".join(odd) if odd else "none among the PGAs run") + "."]
    if cfg.tilt:
        L += ["", "| variant | seed | onset (deg) | reaction drop (deg) | first blocks | wall (s) |",
              "|---|---|---|---|---|---|"]
        for r in data["tilt"]:
            L.append(f"| {planmod.VARIANTS[r['variant']][0]} | {r['seed']} | {_f(r.get('collapse_angle_deg'))} | "
                     f"{_f(r.get('reaction_drop_angle_deg'))} | {r.get('first_blocks') or r.get('status')} | "
                     f"{_f(r.get('wall_s'), '.0f')} |")
    L += ["", "## Cost", ""]
    n_runs = c["seismic"]["runs"] + c["tilt"]["runs"]
    core = c["seismic"]["core_s"] + c["tilt"]["core_s"]
    elapsed = sum(t.get("elapsed_s", 0.0) for t in timing)
    loads = [t for t in timing if t.get("load_average_start")]
    L.append(f"Runs: {n_runs} ({c['tilt']['runs']} tilt, {c['seismic']['runs']} seismic in "
             f"{max([t.get('rounds', 0) for t in timing] or [0])} round(s) of the collapse analyses); "
             f"{core / 60:.1f} core-minutes of "
             f"run time (each run's wall time from start to summary, one thread)"
             + (f", {c['seismic']['mean_wall_s']:.0f} s per seismic run on average (longest "
                f"{c['seismic']['max_wall_s']:.0f} s), {c['seismic']['wall_per_simulated_s']:.2f} s of wall time per "
                "simulated second" if c["seismic"]["mean_wall_s"] else "")
             + f"; the study's elapsed time over {len(timing)} invocation(s) of `run`: {elapsed / 60:.1f} min "
               "(including validation, reused runs and post-processing; the machine's other load included"
             + (f": load average {', '.join(str(t['load_average_start'][0]) for t in loads)} at the start"
                if loads else "") + ").")
    L += ["", "## Assumptions", "",
          "* **ASSUMED**: the records are FEMA P695 far-field stand-ins for the Sacsayhuaman paper's records "
          "(drystone/motions/catalogue.py), cut to their strong-motion windows.",
          "* **ASSUMED**: generated stone outlines (seeded), not surveyed ones; the polygonal walls' end and base "
          "conditions follow the coursed section's rule (stones at the ends held, stones on the platform fixed).",
          "* **ASSUMED**: collapse is monotonic in PGA (the bracket's premise); the seeds are the only source of "
          "spread (one friction coefficient and stiffness, Table 1's).",
          "* **ASSUMED**: the tilt rate (1 deg/s near collapse, the tilt study's faster protocol) is slow enough for "
          "these 4 m walls; the tilt study checked it (0.2 deg/s) on the 1.5 m Santa-Cruz wall only.", ""]
    return markdown.write(cfg.out_dir / "report.md", "\n".join(L) + "\n")  # and report.html beside it
