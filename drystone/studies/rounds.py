"""Bisection searches run as rounds of sweeps, resumable: the machinery the shape study
(drystone/studies/shape/) and the site study (drystone/studies/site/) share.

A search (``Search``) is one bisection over one quantity, a PGA in g or a water level in
m, on its own grid (drystone/analyses/bisect.py: ``low`` assumed safe and not run,
``cap`` the highest value run, ``resolution`` the final bracket's width). ``job(x)`` gives
the sweep job of the run at x (as drystone.sweep.load builds it from a round file: the
common overrides, the run's own ``own(x)``, then ``case.name=<sweep>/<run>``), ``read(out)``
the outcome of a finished run folder ({"status": "done", "collapsed": bool, ...} or a
failure).

``follow`` replays a search through outcomes: the bracket, the runs so far and the next
job. ``run_rounds`` writes one sweep file per round (``<rounds_dir>/<prefix>NN.toml``)
holding the next run of every open search and runs it with drystone.sweep (finished runs
with the same fingerprint are skipped, so an interrupted study continues where it stopped).
Only outcomes confirmed by this invocation's sweeps (run, or skipped as finished with the
same inputs) steer the bisection. ``on_disk`` reads a job's outcome from its folder (for a
report, which replays every search from the runs on disk).
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from drystone import paths, sweep, tomlio
from drystone.analyses import bisect

#: most bisection rounds of one invocation (a search needs at most log2(cap / resolution) + 1)
MAX_ROUNDS = 30


class StudyFolders:
    """Where a study configuration writes (a mixin of the studies' ``Config`` dataclasses,
    which give ``out`` and ``results_root``): ``results`` (results/ or the tests' folder),
    ``out_dir`` = results/<out>/ (plan, rounds, report) and ``records_dir`` within it."""

    @property
    def results(self) -> Path:
        return Path(self.results_root) if self.results_root else paths.RESULTS

    @property
    def out_dir(self) -> Path:
        return self.results / self.out

    @property
    def records_dir(self) -> Path:
        return self.out_dir / "records"


@dataclass(frozen=True)
class Search:
    """One bisection search (module docstring); ``key`` identifies it in the results,
    ``value_key`` names the searched quantity in each run's row (e.g. "pga_g", "level_m")."""

    key: dict
    low: float
    cap: float
    resolution: float
    job: Callable[[float], sweep.Job]
    own: Callable[[float], list]
    read: Callable[[Path], dict]
    value_key: str = "pga_g"


def follow(search: Search, outcome) -> dict:
    """Follow one search's bisection through ``outcome(job) -> dict | None``; returns its
    state: ``status`` done (bracket final), pending (``next`` job to run at ``next_value``),
    failed (a run failed or is unreadable); the bracket and the runs so far, with the
    search's ``key`` entries."""
    observed, runs = {}, []
    for _ in range(MAX_ROUNDS):
        b = bisect.bracket(observed, search.low, search.cap, search.resolution)
        base = {**search.key, "bracket": b.as_dict(), "runs": runs}
        if b.done:
            return dict(base, status="done", next=None)
        job = search.job(b.next_g)
        o = outcome(job)
        if o is None:
            return dict(base, status="pending", next=job, next_value=b.next_g)
        runs.append(dict(o, name=job.name, **{search.value_key: b.next_g}))
        if o["status"] != "done":
            return dict(base, status="failed", next=None, error=o.get("error"))
        observed[b.next_g] = o["collapsed"]
    raise RuntimeError(f"{search.key}: no bracket after {MAX_ROUNDS} runs")


def on_disk(job: sweep.Job, read) -> dict | None:
    """The outcome of a job from its folder (finished with the same overrides; the inputs'
    fingerprint is not checked here), a failure, or None (not run)."""
    d = Path(job.out_dir)
    if sweep.finished(job):
        return read(d)
    if (d / "FAILED.txt").is_file():
        return {"status": "failed", "error": (d / "FAILED.txt").read_text(errors="replace").splitlines()[0][:300]}
    return None


def write_if_changed(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` (atomically) unless it already holds it: a study's inputs
    (sweep files, records, geometries) keep their dates and fingerprints when unchanged."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text() != text:
        tmp = path.with_suffix(".tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
    return path


def write_sweep(path: Path, name: str, case: Path, runs: list, common: list, header: str) -> Path:
    """A sweep file (drystone.tomlio.sweep_file) with the base case relative to the file's
    folder, rewritten only when different (so a finished run is recognised)."""
    return write_if_changed(path, tomlio.sweep_file(name, os.path.relpath(case, path.parent), runs, common, header))


def count(summary: dict, res: dict) -> None:
    """Add a sweep's result (drystone.sweep.run) to a study's running ``summary``: runs run,
    reused, failed, interrupted. A run that several sweeps of one invocation list (a bracket's
    end that a finer search reuses) counts once (``runs_seen``: the names counted so far)."""
    seen = summary.setdefault("runs_seen", [])
    for name, st in res["runs"].items():
        if name in seen:
            continue
        if st["status"] == "done":
            summary["runs_run"] += 1
            seen.append(name)
        elif str(st["status"]).startswith("skipped"):
            summary["runs_reused"] += 1
            seen.append(name)
    summary["failed"] += res["failed"]
    summary["interrupted"] = res["interrupted"]


def run_rounds(searches: list[Search], *, rounds_dir: Path, prefix: str, sweep_name: str, case: Path,
               common: list, label: str, summary: dict, workers=None, backend="local", address=None,
               results: Path | None = None, order=None, log=print) -> int:
    """Bisection rounds until every search is done or failed, or the sweep is interrupted
    (module docstring); ``order(state)`` sorts each round's runs (e.g. longest first).
    Updates ``summary`` (``count``); returns the number of rounds run."""
    verified: dict[str, dict] = {}
    k = 0
    for k in range(1, MAX_ROUNDS + 1):
        states = [(s, follow(s, lambda job: verified.get(job.name))) for s in searches]
        todo = [(s, st) for s, st in states if st["status"] == "pending"]
        if not todo:
            return k - 1
        if order is not None:
            todo.sort(key=lambda p: order(p[1]))
        runs = [(st["next"].name, s.own(st["next_value"])) for s, st in todo]
        path = write_sweep(rounds_dir / f"{prefix}{k:02d}.toml", sweep_name, case, runs, common,
                           f"generated by {label}, bisection round {k}: the next run of {len(runs)} open "
                           "search(es); do not edit")
        log(f"[{label}] round {k}: {len(runs)} run(s) ({path})")
        res = sweep.run(path, workers, backend, address, results=results)
        count(summary, res)
        for s, st in todo:
            job = st["next"]
            r = res["runs"].get(job.name, {})
            if r.get("status") == "done" or str(r.get("status")).startswith("skipped"):
                verified[job.name] = s.read(Path(job.out_dir))
            elif r.get("status") == "failed":
                verified[job.name] = {"status": "failed", "error": r.get("error", "")[:300]}
        if summary["interrupted"]:
            break
    return k


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
    p.write_text(json.dumps(log, indent=1) + "\n")
    return summary


def main(argv, prog: str, doc: str, configs: dict, plan, run, report, tag: str) -> int:
    """The command line of a study of bisection rounds (``python -m drystone.studies.NAME
    {plan,run,report,all} [--config ...] [--workers N] [--dask ADDRESS]``): ``plan(cfg)``
    returns a one-line description, ``run(cfg, workers=, backend=, address=)`` a summary
    (``count``, ``finish``), ``report(cfg)`` the report's path. Exit 130 when interrupted,
    1 when ``run`` alone had failed runs."""
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
    if a.step in ("run", "all"):
        r = run(cfg, workers=a.workers, backend="dask" if a.dask else "local", address=a.dask)
        print(f"[{tag}] {r['rounds']} round(s), {r['runs_run']} run(s) run, {r['runs_reused']} reused, "
              f"{len(r['failed'])} failed, {r['elapsed_s'] / 60:.1f} min")
        if r["interrupted"]:
            return 130
        if a.step == "run":
            return 1 if r["failed"] else 0
    path = report(cfg)
    print(path.read_text())
    print(f"report: {path}")
    return 0
