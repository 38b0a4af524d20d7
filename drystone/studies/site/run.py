"""Running the site study: resumable sweeps (drystone.sweep) and bisection rounds
(drystone/studies/rounds.py), in this order:

1. ``plan`` (plan.py): records, caps, tilt sweep files;
2. the tilt runs (one sweep file per wall: each wall has its own base case);
3. the retained wall's static runs: dry (the bisection's premise: it stands without water),
   then the water level at failure by bisection (``rounds/water_NN.toml``);
4. the PGA at collapse of every wall, site, record and polarity by bisection, the retained
   wall first (``rounds/<wall>_NN.toml``; one base case per wall), then, for a wall with a
   finer grid (``refine_g``), a second bisection inside each bracket
   (``rounds/<wall>_refine_NN.toml``).

A wall whose runs the package refuses before YADE (``sweep.validate``) is left out and its
refusal reported. Finished runs with the same inputs are skipped, so an interrupted study
continues where it stopped; ``timing.json`` logs every invocation (elapsed time, runs run and
reused, the machine's load average).

Collapse of a seismic run: shape.study's ``seismic_outcome`` (at least one stone collapsed as
the Sacsayhuaman study reads it, at the end of the run). Failure of a static run: the same
reading, from the end of the gravity ramp (t = 1 s, when the soil's load is fully on).
"""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

from drystone import atomic
from drystone import sweep
from drystone.studies import rounds
from drystone.studies.shape import study as shape_study
from drystone.studies.site import plan as planmod

LABEL = "drystone/studies/site"


def seismic_job(cfg, wall: str, site: str, record: str, polarity: str, pga_g: float) -> sweep.Job:
    """The sweep job of one seismic run, as drystone.sweep.load builds it from a round file."""
    name = planmod.seismic_run_name(wall, site, record, polarity, pga_g)
    over = (planmod.common_overrides(cfg) + planmod.seismic_overrides(cfg, wall, site, record, polarity, pga_g)
            + [f"case.name={cfg.runs}/{name}"])
    return sweep.Job(name, str(planmod.record_case(wall)), over, str(cfg.results / cfg.runs / name))


def static_job(cfg, level_m: float | None) -> sweep.Job:
    name = planmod.static_run_name(level_m)
    over = planmod.static_common(cfg) + planmod.static_overrides(level_m) + [f"case.name={cfg.runs}/{name}"]
    return sweep.Job(name, str(planmod.STATIC_CASE), over, str(cfg.results / cfg.runs / name))


def tilt_job(cfg, wall: str) -> sweep.Job:
    name = planmod.tilt_run_name(wall)
    return sweep.Job(name, str(planmod.WALLS[wall][2]), [f"case.name={cfg.runs}/{name}"],
                     str(cfg.results / cfg.runs / name))


def surface_pga(out: Path) -> float | None:
    """The PGA at the surface (g) of a run with a site (spec.json's excitations), else None."""
    spec = rounds.read_json(Path(out) / "spec.json") or {}
    for ex in spec.get("excitations", []):
        if ex.get("site"):
            return ex["site"].get("pga_surface_g")
    return None


def seismic_outcome(out: Path) -> dict:
    """shape.study's ``seismic_outcome`` with the surface PGA of a run with a site."""
    o = shape_study.seismic_outcome(out)
    return dict(o, pga_surface_g=surface_pga(out)) if o.get("status") == "done" else o


def tilt_outcome(out: Path) -> dict:
    """shape.study's ``tilt_outcome`` with the onset's time (s) and the time the tilt began
    (the end of the gravity stage): a wall whose stones creep from the gravity stage on (the
    retained wall, as its soil's load comes on) has an onset before any tilt."""
    o = shape_study.tilt_outcome(out)
    if o.get("status") != "done":
        return o
    s = rounds.read_json(Path(out) / "summary.json") or {}
    spec = rounds.read_json(Path(out) / "spec.json") or {}
    tilt0 = next((st["start"] for st in spec.get("stages", []) if st.get("type") == "tilt"), None)
    return dict(o, onset_time_s=(s.get("collapse") or {}).get("time_s"), tilt_start_s=tilt0)


def seismic_search(cfg, plan: dict, wall: str, site: str, record: str, polarity: str) -> rounds.Search:
    cap = plan["caps"][planmod.search_id(wall, site, record, polarity)]["cap_g"]
    return rounds.Search({"wall": wall, "site": site, "record": record, "polarity": polarity}, 0.0, cap,
                         cfg.resolution_g[wall],
                         lambda p: seismic_job(cfg, wall, site, record, polarity, p),
                         lambda p: planmod.seismic_overrides(cfg, wall, site, record, polarity, p),
                         seismic_outcome)


def refine_search(cfg, coarse: rounds.Search, state: dict) -> rounds.Search | None:
    """The finer bisection (``cfg.refine_g``) inside a finished coarse search's bracket (its
    ends were run: the standing low end is not run again, the collapsing high end is the
    cap, run last, i.e. reused); None where the wall has no finer grid, the coarse search is
    not done or it stood at its cap."""
    res = cfg.refine_g.get(coarse.key["wall"])
    b = state.get("bracket") or {}
    if not res or state["status"] != "done" or b.get("censored"):
        return None
    return rounds.Search(dict(coarse.key, stage="refine"), b["low_g"], b["high_g"], res, coarse.job, coarse.own,
                         coarse.read)


def refine_searches(cfg, plan: dict, wall: str) -> list[rounds.Search]:
    """The finer searches of a wall whose coarse searches are done (from the runs on disk)."""
    out = []
    for s in seismic_searches(cfg, plan, wall):
        r = refine_search(cfg, s, rounds.follow(s, lambda j, s=s: rounds.on_disk(j, s.read)))
        if r is not None:
            out.append(r)
    return out


def water_search(cfg) -> rounds.Search:
    return rounds.Search({"search": "water"}, 0.0, cfg.level_cap_m, cfg.level_resolution_m,
                         lambda z: static_job(cfg, z), planmod.static_overrides, shape_study.seismic_outcome,
                         value_key="level_m")


def seismic_searches(cfg, plan: dict, wall: str) -> list[rounds.Search]:
    return [seismic_search(cfg, plan, wall, s, r, pol) for s in cfg.sites for r in cfg.records
            for pol in cfg.polarities[wall]]


def refused_walls(cfg) -> dict[str, str]:
    """Walls whose first run the package refuses before YADE, with the refusal (the retained
    wall before the engines took [[loads]])."""
    from drystone.model.case import CaseError

    out = {}
    for w in cfg.walls:
        try:
            sweep.validate([seismic_job(cfg, w, "rock", cfg.records[0], "+", cfg.resolution_g[w])])
        except CaseError as exc:
            if w == "free":
                raise
            out[w] = str(exc)
    return out


def run(config="full", workers=None, backend="local", address=None) -> dict:
    """Plan, tilt, static and water, then the seismic rounds (module docstring). Returns
    {"rounds", "runs_run", "runs_reused", "failed", "interrupted", "refused", "elapsed_s", ...}."""
    cfg = planmod.get(config)
    t0 = time.time()
    planmod.write_records(cfg)  # the runs validated next read them
    refused = refused_walls(cfg)
    atomic.write_text(cfg.out_dir / "refused.json", json.dumps(refused, indent=1) + "\n")
    for w, why in refused.items():
        print(f"[site] wall {w} left out: {why}", flush=True)
    walls = [w for w in cfg.walls if w not in refused]
    plan = planmod.build(cfg, walls)
    summary = {"rounds": {}, "runs_run": 0, "runs_reused": 0, "interrupted": False, "refused": refused,
               "failed": [], "workers": workers, "backend": backend, "cores": os.cpu_count(),
               "load_average_start": rounds.load_average()}
    kw = {"workers": workers, "backend": backend, "address": address, "results": cfg.results}
    log = lambda m: print(m, flush=True)  # noqa: E731

    def sweep_once(path):
        rounds.count(summary, sweep.run(path, kw["workers"], kw["backend"], kw["address"], results=cfg.results))
        return not summary["interrupted"]

    if cfg.tilt:
        for path in planmod.tilt_sweep(cfg, walls):
            if not sweep_once(path):
                return rounds.finish(cfg.out_dir, summary, t0)
    if "retained" in walls and cfg.water:
        path = rounds.write_sweep(cfg.out_dir / "static.toml", cfg.runs, planmod.STATIC_CASE,
                                  [(planmod.static_run_name(None), planmod.static_overrides(None))],
                                  planmod.static_common(cfg),
                                  f"generated by {LABEL} (config {cfg.name!r}): the retained wall, dry, static")
        if not sweep_once(path):
            return rounds.finish(cfg.out_dir, summary, t0)
        dry = rounds.on_disk(static_job(cfg, None), shape_study.seismic_outcome)
        if dry and dry.get("status") == "done" and not dry["collapsed"]:
            summary["rounds"]["water"] = rounds.run_rounds(
                [water_search(cfg)], rounds_dir=cfg.out_dir / "rounds", prefix="water_", sweep_name=cfg.runs,
                case=planmod.STATIC_CASE, common=planmod.static_common(cfg), label=f"{LABEL} water", summary=summary,
                log=log, **kw)
        else:
            log("[site] the retained wall does not stand dry: no water-level search")
        if summary["interrupted"]:
            return rounds.finish(cfg.out_dir, summary, t0)
    for w in sorted(walls, key=lambda w: w != "retained"):
        summary["rounds"][w] = rounds.run_rounds(
            seismic_searches(cfg, plan, w), rounds_dir=cfg.out_dir / "rounds", prefix=f"{w}_", sweep_name=cfg.runs,
            case=planmod.record_case(w), common=planmod.common_overrides(cfg), label=f"{LABEL} {w}",
            summary=summary, log=log, order=lambda st: -plan["records"][st["record"]]["duration_s"], **kw)
        if summary["interrupted"]:
            break
        fine = refine_searches(cfg, plan, w)
        if fine:
            summary["rounds"][f"{w} refine"] = rounds.run_rounds(
                fine, rounds_dir=cfg.out_dir / "rounds", prefix=f"{w}_refine_", sweep_name=cfg.runs,
                case=planmod.record_case(w), common=planmod.common_overrides(cfg), label=f"{LABEL} {w} refine",
                summary=summary, log=log, order=lambda st: -plan["records"][st["record"]]["duration_s"], **kw)
        if summary["interrupted"]:
            break
    return rounds.finish(cfg.out_dir, summary, t0)
