"""What the shape study (drystone/studies/shape/) and the site study (drystone/studies/site/)
share: where a configuration writes (``StudyFolders``), the ``collapse`` analysis's search
set to their grid (``search_params``), the ``tilt`` analysis set to their tilt cases
(``tilt_protocol``), reading the analyses' JSON into the rows their reports use
(``search_state``, ``tilt_row``), the runs made and reused (``count_runs``), the timing log
(``finish``) and their command line (``main``). Every run is made by drystone/analyses/ (tilt,
collapse): resumable, finished runs with the same fingerprint reused, local pool or Dask.
"""
from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

from drystone import atomic
from drystone import paths


class StudyFolders:
    """Where a study configuration writes (a mixin of the studies' ``Config`` dataclasses,
    which give ``out`` and ``results_root``): ``results`` (results/ or the tests' folder),
    ``out_dir`` = results/<out>/ (plan, the analyses, report) and ``records_dir`` within it."""

    @property
    def results(self) -> Path:
        return Path(self.results_root) if self.results_root else paths.RESULTS

    @property
    def out_dir(self) -> Path:
        return self.results / self.out

    @property
    def records_dir(self) -> Path:
        return self.out_dir / "records"


#: most runs of one search (collapse's ``max_runs``): a grid of 2^n steps needs about n + 2
MAX_RUNS = 30


def search_params(cap_g: float, resolution_g: float) -> dict:
    """The ``collapse`` analysis's search (drystone/analyses/ida.py) set to the studies'
    bisection grid: the first run at half the cap, the cap next when the wall stood there,
    then the middles of the bracket until it is ``resolution_g`` wide, no fill-in. For a cap of
    2^n grid steps every PGA it runs is a point of the grid the studies bisected before."""
    return {"start": cap_g / 2, "factor": 2.0, "cap": cap_g, "tolerance": resolution_g, "fill": None,
            "max_runs": MAX_RUNS}


#: the small configs' shortened protocol (a pipeline check, not a result): gravity ramped over
#: 0.25 s and held to 0.5 s (the cases': 1 s and 2 s), and their tilts 8 deg/s to 5 deg, then 4
#: deg/s until collapse and 0.5 s after it (the cases': 2 and 1 deg/s, 3 s): a quarter to a
#: third of the simulated time of a tilt run
QUICK_GRAVITY = {"duration": 0.5, "ramp": 0.25}
QUICK_TILT = {"rate": 4.0, "lead_rate": 8.0, "after_collapse": 0.5}


def quick_note() -> str:
    """The small configs' shortened protocol in words (their notes)."""
    return (f"gravity held {QUICK_GRAVITY['duration']:g} s, tilts at {QUICK_TILT['lead_rate']:g} then "
            f"{QUICK_TILT['rate']:g} deg/s and {QUICK_TILT['after_collapse']:g} s after the collapse")


def quick_gravity(quick: bool) -> list[str]:
    """The overrides of the first (gravity) stage that shorten it to ``QUICK_GRAVITY`` where
    ``quick`` (a small config), none otherwise."""
    from drystone import tomlio

    return [f"stages.0.{k}={tomlio.value(v)}" for k, v in QUICK_GRAVITY.items()] if quick else []


def tilt_protocol(case, quick: bool = False) -> dict:
    """The keywords of drystone.analyses.tilt.tilt that make the tilt of a study's tilt case
    (its stages after gravity: a lead-in tilt ``to_deg``, then a tilt ``until_collapse``): the
    same run as the case itself (towards, rates, largest tilt, time after the collapse);
    ``quick`` (a small config): the rates and the time after the collapse of ``QUICK_TILT``."""
    from drystone.model import case as casemod

    st = [x for x in casemod.load(case)["stages"] if x.get("type") == "tilt"]
    last = st[-1]
    if not last.get("until_collapse") or len(st) > 2 or (len(st) == 2 and "to_deg" not in st[0]):
        raise ValueError(f"{case}: a study's tilt case has a lead-in tilt (to_deg) and a tilt until_collapse")
    lead = (float(st[0]["to_deg"]), float(st[0]["rate_deg_s"])) if len(st) == 2 else None
    p = {"towards": (last["towards"],), "rate": float(last["rate_deg_s"]), "lead": lead,
         "max_deg": float(last["max_deg"]), "after_collapse": float(last["after_collapse"])}
    if quick:
        p.update(rate=QUICK_TILT["rate"], after_collapse=QUICK_TILT["after_collapse"],
                 lead=lead and (lead[0], QUICK_TILT["lead_rate"]))
    return p


def _run_cost(run_dir: Path) -> dict:
    info = read_json(Path(run_dir) / "run_info.json") or {}
    return {"simulated_s": info.get("simulated_time_s"), "yade_wall_s": info.get("wall_time_s"),
            "steps": info.get("steps")}


def run_row(o: dict, run_dir: Path) -> dict:
    """A run's outcome (drystone/analyses/common.py ``outcome``, or a collapse.json run) with
    its simulated time and cost (run_info.json) and its largest out-of-plane residual in mm."""
    row = {**_run_cost(run_dir), **o}
    if o.get("largest_out_of_plane_m") is not None:
        row["max_out_of_plane_mm"] = 1e3 * o["largest_out_of_plane_m"]
    return row


def search_state(key: dict, rec: dict | None, out_dir: Path) -> dict:
    """One record's search of a collapse analysis (collapse.json ``records.<stem>``, the
    analysis in ``out_dir``) as the studies' reports read it: ``status`` done (bracketed or
    censored), pending (no result yet), failed or budget; ``bracket`` {low_g, high_g, done,
    censored, estimate_g, non_monotonic}; ``runs`` (PGA order) with the run's simulated time
    and its largest out-of-plane residual in mm."""
    if rec is None:
        return dict(key, status="pending", bracket=None, runs=[])
    runs = [run_row(r, Path(out_dir) / "runs" / r["name"]) for r in rec["runs"]]
    st = rec["status"]
    b = None
    if st in ("bracketed", "censored"):
        lo, hi = rec["pga_at_collapse_g"] or (rec["censored_at_g"], None)
        b = {"low_g": lo, "high_g": hi, "done": True, "censored": st == "censored",
             "estimate_g": None if hi is None else 0.5 * (lo + hi),
             "non_monotonic": rec.get("standing_above_collapse_g") or [], "runs": len(runs)}
    out = dict(key, status="done" if b else st, bracket=b, runs=runs)
    if rec.get("error"):
        out["error"] = rec["error"]
    return out


def tilt_row(key: dict, res: dict | None, out_dir: Path) -> dict:
    """One tilt analysis's direction (tilt.json ``directions.<d>``, the analysis in
    ``out_dir``) as the studies' reports read it: the onset (``collapse_angle_deg``, the
    analysis's headline) and the reaction-drop angle, the first stone, the run's cost."""
    if res is None:
        return dict(key, status="pending")
    if res.get("status") != "done":
        return dict(key, status="failed", error=res.get("error"))
    return dict(key, status="done", collapse_angle_deg=res.get("onset_deg"),
                reaction_drop_angle_deg=res.get("reaction_drop_deg"),
                first_blocks=[res["first_stone"]] if res.get("first_stone") is not None else None,
                wall_s=res.get("wall_s"), **_run_cost(Path(out_dir) / res["run"]))


def count_runs(folders, t0: float) -> tuple[int, int, int]:
    """(runs made since ``t0``, runs reused, rounds) over the analyses' folders: a run folder
    whose run_info.json is newer than ``t0`` was run by this invocation; rounds: the most
    round sweep files of one analysis."""
    run = reused = rounds = 0
    for f in folders:
        f = Path(f)
        for d in (f / "runs").glob("*/run_info.json"):
            if d.stat().st_mtime >= t0:
                run += 1
            else:
                reused += 1
        rounds = max(rounds, len(list((f / "sweeps").glob("round-*.toml"))))
    return run, reused, rounds


def write_if_changed(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` (atomically) unless it already holds it: a study's inputs
    (sweep files, records, geometries) keep their dates and fingerprints when unchanged."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        atomic.write_text(path, text)
    else:
        atomic.record(path)  # the package's, for make clean, even if written before it kept lists
    return path


def read_json(p: Path):
    """A JSON file's content, or None when it is missing or unreadable."""
    try:
        return json.loads(Path(p).read_text())
    except (OSError, ValueError):
        return None


def load_average() -> list | None:
    """The machine's 1, 5 and 15 min load averages (a study's cost is measured beside them)."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def finish(out_dir: Path, summary: dict, t0: float) -> dict:
    """Close a study invocation's ``summary``: elapsed time since ``t0`` (s), load average,
    appended to ``<out_dir>/timing.json`` with its start date."""
    summary["elapsed_s"] = time.time() - t0
    summary["load_average_end"] = load_average()
    p = Path(out_dir) / "timing.json"
    log = read_json(p) or []
    log.append({"started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(t0)),
                **{k: v for k, v in summary.items() if k != "runs_seen"}})
    atomic.write_text(p, json.dumps(log, indent=1) + "\n")
    return summary


def main(argv, prog: str, doc: str, configs: dict, plan, run, report, tag: str) -> int:
    """The command line of a study of walls' analyses (``python -m drystone.studies.NAME
    {plan,run,report,all} [--config ...] [--workers N] [--dask ADDRESS]``): ``plan(cfg)``
    returns a one-line description, ``run(cfg, workers=, backend=, address=)`` a summary
    (``count``, ``finish``), ``report(cfg)`` the report's path. Exit 130 when interrupted,
    1 when runs failed or the report is incomplete (a search pending, failed or refused:
    ``incomplete``), with one line on standard error saying what is missing."""
    import argparse

    ap = argparse.ArgumentParser(prog=prog, description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("plan", "run", "report", "all"))
    ap.add_argument("--config", choices=tuple(configs), default="full")
    ap.add_argument("--workers", type=int, default=None, help="parallel runs (default: cores)")
    ap.add_argument("--dask", metavar="ADDRESS", default=None, help="Dask scheduler address, or 'local'")
    a = ap.parse_args(argv)
    cfg = configs[a.config]
    if a.step == "plan":
        print(plan(cfg))
        return 0
    failed = []
    if a.step in ("run", "all"):
        r = run(cfg, workers=a.workers, backend="dask" if a.dask else "local", address=a.dask)
        print(f"[{tag}] {r['rounds']} round(s), {r['runs_run']} run(s) run, {r['runs_reused']} reused, "
              f"{len(r['failed'])} failed, {r['elapsed_s'] / 60:.1f} min")
        if r["interrupted"]:
            return 130
        failed = r["failed"]
        if a.step == "run":
            return 1 if failed else 0
    path = report(cfg)
    print(path.read_text())
    print(f"report: {path}")
    missing = incomplete(cfg.out_dir / f"{tag}.json")
    if failed or missing:
        print(f"error: {path}: incomplete: {missing or 'no search missing'}"
              + (f"; {len(failed)} run(s) of this invocation failed: {', '.join(map(str, failed[:5]))}" if failed else "")
              + " (run the study again to continue or retry)", file=sys.stderr)
        return 1
    return 0


def missing_text(status: str) -> str:
    """A report's cell for a search without a result: MISSING and why (never a bracket-like
    "open" that reads as a result)."""
    why = {"pending": "not run yet", "failed": "a run failed"}.get(status, status)
    return f"**MISSING** ({why})"


def incomplete(report_json: Path) -> str:
    """What a study's report (its ``<tag>.json``: ``status`` counts of the searches by state,
    ``refused`` walls) lacks, in words, or "" when every search is done."""
    data = read_json(report_json)
    if not isinstance(data, dict):
        return f"{report_json} unreadable"
    status = data.get("status") or {}
    parts = [f"{n} search(es) {k}" for k, n in status.items() if k != "done" and n]
    refused = data.get("refused")
    if isinstance(refused, list) and refused:
        parts.append(f"walls not run: {', '.join(map(str, refused))}")
    return "; ".join(parts)
