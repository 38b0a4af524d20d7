"""Friction studies of Ogawa et al. §5 with the 1D model, and the report.

Sets of friction coefficients (mu10, mu20, mu31, mu41, mu42, mu52):
* ``uniform_0.40``: all 0.40 (the 3D case ``cases/ogawa_kobe_3d.toml`` uses the same);
* ``uniform_pm0.02``: 0.40 with a uniform random variation of +-0.02 (seeded), as §5;
* ``table4_run1..3``: the paper's Table 4;
* ``random_001..N``: large variation, each coefficient uniform in [0.25, 0.55] (the span of
  Table 4, 0.29-0.52, widened), seeded.
Each set runs the record ``runs`` times in succession without resetting (the experiment
applied Kobe five times). The experimental pattern (paper §5, Figure 7) is: blocks 3 and 4
have the two largest residual displacements and block 2 the smallest.

Outputs in ``results/ogawa/``: ``summary.json`` (per set and model, residual displacement
of each block in mm after each run; for the random study the number of sets and the
fraction showing the experimental pattern, overall and split by whether the base joints
are rougher than the upper ones), ``report.md`` and PNG bar charts.

Input level: the JMA Kobe record's PGA is 818 gal = 818 cm/s^2, i.e. 818 / 980.665 =
0.834 g (``KOBE_PGA_G``, from ``data/ogawa/paper_values.toml``; not 0.818 g).

3D model of the named sets (``run_3d``, ``make ogawa3d``): the sweep ``SWEEP_3D``
(generated into results/ogawa/sweeps/, status in results/ogawa_kobe_3d_sets/sweep.json) runs
cases/ogawa_kobe_3d.toml with each NAMED set into ``folder_3d(name)``, skipping finished runs.

3D studies (``orientation_study``, from the sweeps ``cases/sweeps/ogawa_pga.toml`` and
``ogawa_cumulative.toml``, run by ``make ogawa-pga``): both readings of the paper's block
size (drystone/geometry/ogawa_blocks.py, both ASSUMED), the lowest swept PGA at which an end block
(3 or 5) overturns, and the five runs read two ways: *reset* (every run from the stack as
built: one run, since the model is deterministic) and *cumulative* (each run continues
from the state the previous one left), beside the paper's "about 20 mm" (§5, its 1D model
with mu about 0.4) and "blocks 3 and 4 largest, block 2 smallest" (the experiment, Fig. 7).
"""
from __future__ import annotations

import json
import os
import tomllib
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import drystone
from drystone import atomic
from drystone import paths, sweep, tomlio
from drystone.geometry import ogawa_blocks
from drystone.model.spec import stage_type
from drystone.postprocess import markdown
from drystone.studies.ogawa import mrb1d
from drystone.units import G_STANDARD

OUT = paths.RESULTS / "ogawa"
SEED = 20261122
RANDOM_RANGE = (0.25, 0.55)


def gal_to_g(gal: float) -> float:
    """An acceleration in gal (cm/s^2) in g (1 g = ``G_STANDARD`` = 980.665 gal)."""
    return float(gal) * 1e-2 / G_STANDARD


def paper_values() -> dict:
    """data/ogawa/paper_values.toml (the paper's numbers we compare against)."""
    return tomllib.loads((paths.DATA / "ogawa" / "paper_values.toml").read_text())


#: PGA of the JMA Kobe 1995 NS record, 818 gal, in g: 0.834 g
KOBE_PGA_G = gal_to_g(paper_values()["shaking_table"]["jma_kobe_pga_gal"])


def friction_sets(n_random: int = 50, seed: int = SEED) -> dict[str, dict]:
    """Named friction sets (module docstring), reproducible from ``seed``."""
    rng = np.random.default_rng(seed)
    paper = paper_values()
    sets = {"uniform_0.40": dict.fromkeys(mrb1d.MU_KEYS, 0.40)}
    sets["uniform_pm0.02"] = {k: round(0.40 + rng.uniform(-0.02, 0.02), 4) for k in mrb1d.MU_KEYS}
    for i, (name, mu) in enumerate(paper["table4"].items(), 1):
        sets[f"table4_run{i}"] = {k: float(mu[k]) for k in mrb1d.MU_KEYS}
    for i in range(n_random):
        sets[f"random_{i + 1:03d}"] = {k: round(float(rng.uniform(*RANDOM_RANGE)), 4) for k in mrb1d.MU_KEYS}
    return sets


def kobe(pga_g: float | None = KOBE_PGA_G):
    """The Kobe 1995 record of the catalogue (the user's JMA file, else the FEMA analogue,
    an ASSUMED stand-in), scaled to the JMA record's PGA, 818 gal = 0.834 g
    (``KOBE_PGA_G``), unless ``pga_g`` is None."""
    from drystone.motions import catalogue, processing

    r = catalogue.get("kobe1995")
    return processing.scale_to_pga(r, pga_g=pga_g) if pga_g else r


def experimental_pattern(residual_mm) -> bool:
    """Blocks 3 and 4 move most, block 2 least (|residual| after the last run; a block
    that fell (None) counts as the largest)."""
    d = np.abs(np.array([np.inf if x is None else x for x in residual_mm], float))
    order = np.argsort(-d, kind="stable")
    distinct = d[order[1]] > d[order[2]] and d[1] < np.sort(d)[1]  # no ties at the top two or the bottom
    return bool(distinct and set(order[:2].tolist()) == {2, 3} and int(np.argmin(d)) == 1)


def _run_set(args):
    name, mu, acc, dt, runs, substeps = args
    res = mrb1d.repeated(mrb1d.five_blocks(mu), acc, dt, runs=runs, substeps=substeps)
    return name, [(1e3 * r).tolist() for r in res]


def run(n_random: int = 50, runs: int = 5, substeps: int = 10, record=None, workers: int | None = None,
        out: Path = OUT, progress: bool = True) -> dict:
    """All sets with the 1D model, in parallel; writes summary.json and the report."""
    rec = record if record is not None else kobe()
    sets = friction_sets(n_random)
    out.mkdir(parents=True, exist_ok=True)
    jobs = [(name, mu, rec.acc, rec.dt, runs, substeps) for name, mu in sets.items()]
    results = {}
    workers = workers or os.cpu_count() or 1
    with ProcessPoolExecutor(max_workers=workers) as ex:
        for k, (name, res) in enumerate(ex.map(_run_set, jobs), 1):
            results[name] = res
            if progress:
                print(f"[ogawa 1d] {k}/{len(jobs)} {name}: residual after run {runs} (mm) "
                      + " ".join(f"{x:7.2f}" for x in res[-1]), flush=True)
    summary = {
        "units": "mm, relative to the base, along the shaking direction",
        "record": rec.metadata(), "kobe_pga_g": KOBE_PGA_G, "runs": runs, "substeps": substeps, "step_s": rec.dt / substeps,
        "seed": SEED, "random_range": list(RANDOM_RANGE), "drystone_version": drystone.__version__,
        "sets": {name: {"mu": sets[name], "1d": results[name]} for name in sets},
    }
    summary["random_study"] = pattern_statistics(summary)
    _attach_3d(summary)
    atomic.write_text(out / "summary.json", json.dumps(summary, indent=1))
    report(summary, out)
    return summary


def pattern_statistics(summary: dict) -> dict:
    """How often the random sets show the experimental pattern, overall and split by
    base roughness (mean of mu10, mu20 above or below the mean of the upper joints)."""
    rows = []
    for name, s in summary["sets"].items():
        if not name.startswith("random_"):
            continue
        mu = s["mu"]
        base = 0.5 * (mu["mu10"] + mu["mu20"])
        upper = np.mean([mu[k] for k in ("mu31", "mu41", "mu42", "mu52")])
        rows.append((experimental_pattern(s["1d"][-1]), base > upper))
    n = len(rows)
    hi = [p for p, b in rows if b]
    lo = [p for p, b in rows if not b]
    return {"n_sets": n, "n_pattern": int(sum(p for p, _ in rows)),
            "fraction_pattern": (sum(p for p, _ in rows) / n) if n else None,
            "rougher_base": {"n_sets": len(hi), "n_pattern": int(sum(hi)), "fraction": (sum(hi) / len(hi)) if hi else None},
            "smoother_base": {"n_sets": len(lo), "n_pattern": int(sum(lo)), "fraction": (sum(lo) / len(lo)) if lo else None}}


NAMED = ("uniform_0.40", "uniform_pm0.02", "table4_run1", "table4_run2", "table4_run3")
CASE_3D = paths.CASES / "ogawa_kobe_3d.toml"
#: the sweep running CASE_3D with the NAMED sets (``run_3d``)
SWEEP_3D = "ogawa_kobe_3d_sets"


def folder_3d(name: str, results: Path | None = None) -> Path:
    """Where the 3D run of a named set lives, under ``results`` (default results/):
    ogawa_kobe_3d for uniform_0.40 (the case file as shipped), else ogawa_kobe_3d_<name>."""
    return Path(results or paths.RESULTS) / ("ogawa_kobe_3d" if name == "uniform_0.40" else f"ogawa_kobe_3d_{name}")


def _attach_3d(summary: dict) -> None:
    """Add the 3D model's residuals after each run to every named set that has been run,
    and the orientation / PGA / reset-vs-cumulative study when its sweeps have runs."""
    for name in NAMED:
        p = folder_3d(name) / "summary.json"
        if not p.is_file() or name not in summary.get("sets", {}):
            continue
        # a block that dropped by more than half its height has fallen off the stack:
        # its residual is not a sliding distance (None in the tables, "fell" in the report)
        summary["sets"][name]["3d"] = [r["residual_mm"] for r in run_residuals(folder_3d(name))]
    summary["orientation_study"] = orientation_study()


def _block_dims(geometry: dict) -> dict[int, tuple[float, float]]:
    """Per free block id: (length along x, height), m, from a block file dict."""
    out = {}
    for b in geometry["blocks"]:
        if b["role"] == "free":
            v = np.asarray(b["vertices"], float)
            out[int(b["id"])] = (float(np.ptp(v[:, 0])), float(np.ptp(v[:, 2])))
    return out


def run_residuals(folder: Path) -> list[dict]:
    """The state of the five blocks after each run (each rest stage) of a finished 3D run
    folder: ``residual_mm`` (x displacement relative to the base, mm; None for a block that
    fell, i.e. dropped by more than half its height), ``rotation_deg`` (rotation angle of
    each block, deg) and ``overturned`` (block ids whose rotation exceeds their tipping
    angle atan(length / height), the angle at which the centre of mass passes over the
    edge the block rocks on: it no longer stands on its own base, or it fell)."""
    from drystone.mechanics import rotations
    from drystone.postprocess import summary as summ

    folder = Path(folder)
    s3 = json.loads((folder / "summary.json").read_text())
    dims = _block_dims(json.loads((folder / "geometry.json").read_text()))
    h = summ.load_histories(folder)
    ids = [int(i) for i in h["block_ids"]]
    out = []
    for st in s3["stage_residuals"]:
        if st["kind"] != "rest":
            continue
        i = int(np.argmin(np.abs(h["t"] - st["sample_time_s"])))
        rot = np.degrees(np.linalg.norm(rotations.relative_rotation_vectors(h["quat"][i], h["quat0"]), axis=1))
        res, angle, over = [], [], []
        for b in range(1, 6):
            lx, hz = dims[b]
            d = st["displacement_m"][str(b)]
            fell = d is None or d[2] < -0.5 * hz  # None: it had left the model (summary.stage_residuals)
            a = float(rot[ids.index(b)])
            res.append(None if fell else 1e3 * d[0])
            angle.append(a)
            if fell or a > np.degrees(np.arctan2(lx, hz)):
                over.append(b)
        out.append({"residual_mm": res, "rotation_deg": angle, "overturned": over})
    return out


def _run_meta(folder: Path) -> dict:
    """Orientation (geometry.json) and PGA of the first excitation (summary.json) of a run."""
    s3 = json.loads((Path(folder) / "summary.json").read_text())
    gen = json.loads((Path(folder) / "geometry.json").read_text()).get("generator", {})
    exc = s3["inputs"]["excitations"]
    return {"orientation": gen.get("orientation", ogawa_blocks.DEFAULT_ORIENTATION),
            "assumed": gen.get("assumed", []),
            "pga_g": float(exc[0]["pga_g"]) if exc else None,
            "record": {k: exc[0].get(k) for k in ("event", "station", "component", "scale_factor")} if exc else None,
            "runs": sum(1 for st in s3["inputs"]["stages"] if stage_type(st) == "excitation")}


def _sweep_folders(root: Path) -> list[Path]:
    return sorted(p for p in Path(root).iterdir() if p.is_dir() and (p / "summary.json").is_file()) \
        if Path(root).is_dir() else []


def overturning_onset(levels: list[dict]) -> dict:
    """From runs of one orientation at several PGAs (each ``{"pga_g", "overturned"}``,
    overturned = block ids), the lowest PGA at which an end block (3 or 5) overturned and
    the highest one below it at which none did: the onset lies between the two."""
    levels = sorted(levels, key=lambda r: r["pga_g"])
    ends = set(ogawa_blocks.END_BLOCKS)
    hit = [r["pga_g"] for r in levels if ends & set(r["overturned"])]
    if not hit:
        return {"onset_pga_g": None, "below_g": levels[-1]["pga_g"] if levels else None,
                "levels_g": [r["pga_g"] for r in levels], "monotonic": True}
    first = hit[0]
    below = [r["pga_g"] for r in levels if r["pga_g"] < first]
    above = [r for r in levels if r["pga_g"] >= first]
    return {"onset_pga_g": first, "below_g": below[-1] if below else None,
            "levels_g": [r["pga_g"] for r in levels],
            "monotonic": all(ends & set(r["overturned"]) for r in above)}


def orientation_study(pga_root: Path | None = None, cumulative_root: Path | None = None) -> dict | None:
    """The 3D study of the two block readings (module docstring), from the finished runs of
    the sweeps ogawa_pga (one run from the initial state at each PGA) and ogawa_cumulative
    (five runs in succession at 818 gal); None when neither has a finished run."""
    pga_root = Path(pga_root or paths.RESULTS / "ogawa_pga")
    cumulative_root = Path(cumulative_root or paths.RESULTS / "ogawa_cumulative")
    pga_runs, cum_runs = _sweep_folders(pga_root), _sweep_folders(cumulative_root)
    if not pga_runs and not cum_runs:
        return None
    out: dict = {"kobe_pga_g": KOBE_PGA_G, "orientations": {}, "assumed": {},
                 "pga_sweep_folder": str(pga_root), "cumulative_folder": str(cumulative_root)}
    for folder in pga_runs:
        rr = run_residuals(folder)
        if not rr:  # not a shaking run (no rest stage after a record)
            continue
        m = _run_meta(folder)
        o = out["orientations"].setdefault(m["orientation"], {"pga": [], "reset": None, "cumulative": None})
        out["assumed"][m["orientation"]] = m["assumed"]
        r = rr[-1]
        o["pga"].append({"pga_g": m["pga_g"], "run": folder.name, **r})
        if abs(m["pga_g"] - KOBE_PGA_G) < 5e-4:  # the record's own level: the reset run
            o["reset"] = {"run": folder.name, "record": m["record"], **r}
    for folder in cum_runs:
        rr = run_residuals(folder)
        if not rr:
            continue
        m = _run_meta(folder)
        o = out["orientations"].setdefault(m["orientation"], {"pga": [], "reset": None, "cumulative": None})
        out["assumed"][m["orientation"]] = m["assumed"]
        o["cumulative"] = {"run": folder.name, "pga_g": m["pga_g"], "record": m["record"], "runs": rr}
    for o in out["orientations"].values():
        o["pga"].sort(key=lambda r: r["pga_g"])
        o["onset"] = overturning_onset(o["pga"]) if o["pga"] else None
    return out


def write_sweep_3d(path: Path = OUT / "sweeps" / f"{SWEEP_3D}.toml", results: Path | None = None) -> Path:
    """The sweep file of the 3D model over the NAMED friction sets (generated: the sets come
    from ``friction_sets``): run <set> is CASE_3D with the set's mu, named
    ogawa_kobe_3d_<set>, in its ``folder_3d`` (the sweep's per-run ``out``, relative to
    ``results``, default results/)."""
    mu_sets = friction_sets(0)
    root = Path(results or paths.RESULTS)
    runs = [(n, [f"case.geometry.{k}={v}" for k, v in mu_sets[n].items()] + [f"case.name=ogawa_kobe_3d_{n}"],
             folder_3d(n, root).relative_to(root).as_posix()) for n in NAMED]
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, tomlio.sweep_file(SWEEP_3D, CASE_3D, runs, header="generated by drystone/studies/ogawa/study.py"))
    return path


def run_3d(names=NAMED, workers: int | None = None, backend: str = "local", address: str | None = None) -> dict:
    """The 3D YADE model for the named friction sets, as a resumable sweep (drystone/sweep.py:
    runs finished with the same inputs are skipped; status in results/ogawa_kobe_3d_sets/
    sweep.json); about 4 min per set on one core. Then refresh summary.json and the report."""
    res = sweep.run(write_sweep_3d(), workers, backend, address, only=list(names))
    refresh()
    return res


def refresh(out: Path = OUT) -> None:
    """Re-attach 3D results to summary.json (a summary with only the 3D studies when the
    1D study has not been run) and rewrite the report."""
    p = out / "summary.json"
    out.mkdir(parents=True, exist_ok=True)
    summary = json.loads(p.read_text()) if p.is_file() else {"sets": {}, "kobe_pga_g": KOBE_PGA_G}
    _attach_3d(summary)
    atomic.write_text(p, json.dumps(summary, indent=1))
    report(summary, out)


def bar_chart(name: str, res: dict, path: Path, title: str) -> Path:
    """Residual of each block after each run (the paper's Figures 7-9)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    models = [m for m in ("1d", "3d") if m in res]
    fig, axes = plt.subplots(1, len(models), figsize=(5.5 * len(models), 3.8), squeeze=False)
    for ax, model in zip(axes[0], models):
        data = np.array([[np.nan if x is None else x for x in row] for row in res[model]], float)
        w = 0.8 / len(data)
        for r, row in enumerate(data):
            x = np.arange(1, 6) + (r - (len(data) - 1) / 2) * w
            ax.bar(x, np.nan_to_num(row), w, label=f"run{r + 1}")
            for xi in x[np.isnan(row)]:
                ax.text(xi, 0, "fell", rotation=90, fontsize=6, ha="center", va="bottom")
        ax.set_xticks(range(1, 6))
        ax.set_xlabel("block")
        ax.set_ylabel("residual displacement (mm)")
        ax.set_title(f"{title} - {model.upper()} model", fontsize=9)
        ax.axhline(0, color="k", lw=0.5)
        ax.grid(alpha=0.3, axis="y")
        ax.legend(fontsize=7)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=110)
    plt.close(fig)
    return path


def report(summary: dict, out: Path) -> Path:
    """report.md with the tables and bar charts (the 1D study when it has been run, the 3D
    orientation / PGA / reset-vs-cumulative study when its sweeps have runs)."""
    lines = ["# Ogawa et al.: five blocks under the Kobe 1995 record", ""]
    lines += assumed_lines(summary)
    if "random_study" in summary:
        lines += report_1d(summary, out)
    else:
        lines += ["## 1D friction studies", "", "Not run: `make ogawa`.", ""]
    lines += report_orientation(summary.get("orientation_study"), summary)
    return markdown.write(out / "report.md", "\n".join(lines))  # and report.html beside it


def assumed_lines(summary: dict) -> list[str]:
    """The inputs of this study that the paper does not give, labelled as assumed."""
    rec = summary.get("record") or {}
    event = str(rec.get("event") or "")
    items = [f"Input level: the JMA Kobe record's PGA, 818 gal = 818 / 980.665 g = {KOBE_PGA_G:.3f} g "
             "(the JMA value; the paper does not print it)."]
    if "analogue" in event or not rec:
        items.append("Record: ASSUMED stand-in unless you provide the JMA file (`data/records/user/kobe1995.*`): "
                     + (event or "the catalogue's FEMA P695 Kobe 1995 analogue (docs/motions.md)") + ".")
    items += ["Block orientation: ASSUMED; the paper's \"100x50x100 mm\" has no axis order: "
              + "; ".join(f"`{k}`: {v}" for k, v in ogawa_blocks.READINGS.items()) + "."]
    items += [f"{a[0].upper()}{a[1:]}." for a in ogawa_blocks.ASSUMED_COMMON]
    return ["## Assumed inputs", ""] + [f"* {x}" for x in items] + [""]


def report_1d(summary: dict, out: Path) -> list[str]:
    st = summary["random_study"]
    lines = ["## 1D friction studies (the paper's model, Eqs. 1-5)", "",
             f"Record: {summary['record'].get('event')} at {summary['record'].get('station')} "
             f"({summary['record'].get('component')}), scale factor {summary['record'].get('scale_factor')}, "
             f"PGA {summary['record'].get('pga_g', float('nan')):.3f} g; "
             f"{summary['runs']} runs in succession, Newmark step {summary['step_s']:.1e} s. "
             "Residual displacement of each block relative to the base (mm), after each run. "
             "The 1D model only slides, so it does not depend on the block orientation.", ""]
    for name in NAMED:
        s = summary["sets"][name]
        png = bar_chart(name, s, out / f"{name}.png", name)
        lines += [f"### {name}", "", "mu: " + ", ".join(f"{k} = {v}" for k, v in s["mu"].items()), "",
                  "| model | run | block 1 | block 2 | block 3 | block 4 | block 5 | experimental pattern |",
                  "|---|---|---|---|---|---|---|---|"]
        for model in ("1d", "3d"):
            for r, row in enumerate(s.get(model, []), 1):
                lines.append(f"| {model} | {r} | " + " | ".join("fell" if x is None else f"{x:.2f}" for x in row)
                             + f" | {'yes' if experimental_pattern(row) else 'no'} |")
        lines += ["", f"![{name}]({png.name})", ""]
    lines += ["### Random sets with large variation", "",
              f"{st['n_sets']} sets, each coefficient uniform in {summary['random_range']} (seed {summary['seed']}). "
              f"The experimental pattern (blocks 3 and 4 move most, block 2 least) appears in "
              f"{st['n_pattern']} of {st['n_sets']} sets ({100 * (st['fraction_pattern'] or 0):.0f} %).", "",
              "| base joints (mean of mu10, mu20) | sets | with the pattern | fraction |", "|---|---|---|---|",
              f"| rougher than the upper joints | {st['rougher_base']['n_sets']} | {st['rougher_base']['n_pattern']} | "
              f"{_pct(st['rougher_base']['fraction'])} |",
              f"| smoother than the upper joints | {st['smoother_base']['n_sets']} | {st['smoother_base']['n_pattern']} | "
              f"{_pct(st['smoother_base']['fraction'])} |", ""]
    return lines


def _cell(x, b: int, over: list[int]) -> str:
    if x is None:
        return "fell"
    return f"{x:.1f}" + (" (overturned)" if b in over else "")


def _largest(row: list, over: list[int]) -> str:
    """The two blocks with the largest |residual| (a fallen or overturned block first)."""
    d = [np.inf if (x is None or b in over) else abs(x) for b, x in zip(range(1, 6), row)]
    order = np.argsort(-np.asarray(d), kind="stable")[:2]
    return ", ".join(str(int(k) + 1) for k in sorted(order))


def report_orientation(study: dict | None, summary: dict) -> list[str]:
    """Side-by-side tables: per block reading, the reset and cumulative runs at 818 gal, the
    paper's numbers, and the PGA at which the end blocks start to overturn."""
    paper = paper_values()["shaking_table"]
    lines = ["## 3D model: block orientation, end-block overturning, reset vs cumulative runs", ""]
    if not study:
        return lines + ["Not run: `make ogawa-pga` (sweeps `cases/sweeps/ogawa_pga.toml` and "
                        "`ogawa_cumulative.toml`, about 30 min on 2 cores).", ""]
    lines += [f"Uniform mu = 0.40 on every joint. *Reset*: the record once from the stack as built (the model is "
              f"deterministic, so the paper's five runs read this way are five copies of this run). *Cumulative*: "
              f"five runs in succession, each from the state the previous one left (totals after each run). "
              f"Residual displacement of each block along the shaking direction relative to the base, mm; "
              f"'overturned' = rotated past its tipping angle atan(length / height), 'fell' = dropped by more "
              f"than half its height. Both block readings are ASSUMED.", "",
              "| reading | protocol | after run | block 1 | block 2 | block 3 | block 4 | block 5 | largest | "
              "blocks 3, 4 largest and 2 least |", "|---|---|---|---|---|---|---|---|---|---|"]
    lo, hi = paper["experiment_largest_blocks"], paper["experiment_smallest_block"]
    lines.append(f"| experiment (paper §5, Fig. 7) | five runs | each | | | | | | {lo[0]}, {lo[1]} | yes "
                 f"(block {hi} least) |")
    lines.append(f"| paper's 1D model, mu about 0.4 (§5, Fig. 8) | five runs | each | about "
                 f"{paper['uniform_residual_order_mm']} mm | | | | | "
                 f"{', '.join(str(b) for b in paper['model_uniform_largest_blocks'])} | no |")
    s1 = summary.get("sets", {}).get("uniform_pm0.02", {}).get("1d")
    if s1:
        lines.append("| ours, 1D, mu 0.40 ± 0.02 | reset | 1 (= every run) | "
                     + " | ".join(_cell(x, b, []) for b, x in enumerate(s1[0], 1))
                     + f" | {_largest(s1[0], [])} | {'yes' if experimental_pattern(s1[0]) else 'no'} |")
        for k, row in enumerate(s1, 1):
            lines.append(f"| ours, 1D, mu 0.40 ± 0.02 | cumulative | {k} | "
                         + " | ".join(_cell(x, b, []) for b, x in enumerate(row, 1))
                         + f" | {_largest(row, [])} | {'yes' if experimental_pattern(row) else 'no'} |")
    for name in sorted(study["orientations"]):
        o = study["orientations"][name]
        rows = []
        if o.get("reset"):
            rows.append(("reset", "1 (= every run)", o["reset"]))
        else:
            rows.append(("reset", "not run", None))
        if o.get("cumulative"):
            rows += [("cumulative", str(k), r) for k, r in enumerate(o["cumulative"]["runs"], 1)]
        else:
            rows.append(("cumulative", "not run", None))
        for proto, run, r in rows:
            if r is None:
                lines.append(f"| 3D {name} (assumed) | {proto} | {run} | | | | | | | |")
                continue
            row, over = r["residual_mm"], r["overturned"]
            pat = experimental_pattern([None if b in over else x for b, x in enumerate(row, 1)])
            lines.append(f"| 3D {name} (assumed) | {proto} | {run} | "
                         + " | ".join(_cell(x, b, over) for b, x in enumerate(row, 1))
                         + f" | {_largest(row, over)} | {'yes' if pat else 'no'} |")
    lines += ["", "### PGA at which the end blocks (3 and 5) start to overturn (one run from the stack as built)", "",
              "| reading | PGA levels run (g) | overturned end blocks per level | onset |", "|---|---|---|---|"]
    for name in sorted(study["orientations"]):
        o = study["orientations"][name]
        if not o["pga"]:
            lines.append(f"| {name} (assumed) | not run | | |")
            continue
        per = "; ".join(f"{r['pga_g']:.3g} g: "
                        + (",".join(str(b) for b in r["overturned"] if b in ogawa_blocks.END_BLOCKS) or "none")
                        for r in o["pga"])
        on = o["onset"]
        if on["onset_pga_g"] is None:
            txt = f"none up to {on['below_g']:.3g} g"
        elif on["below_g"] is None:
            txt = f"at or below {on['onset_pga_g']:.3g} g (the lowest level run)"
        else:
            txt = f"between {on['below_g']:.3g} and {on['onset_pga_g']:.3g} g"
        if on["onset_pga_g"] is not None and not on["monotonic"]:
            txt += " (not at every higher level)"
        levels = ", ".join(f"{r['pga_g']:.3g}" for r in o["pga"])
        lines.append(f"| {name} (assumed) | {levels} | {per} | {txt} |")
    lines += ["", f"818 gal = {KOBE_PGA_G:.3f} g is the JMA record's own level.", ""]
    return lines


def _pct(x) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"
