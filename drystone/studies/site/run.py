"""Running the site study on the package's analyses (drystone/analyses/), in this order:

1. ``plan`` (plan.py): records, caps;
2. per wall the ``tilt`` analysis of its tilt case (towards the open side, -y; the case's
   own protocol: drystone/studies/common.py ``tilt_protocol``) into ``tilt/<wall>/``;
3. the retained wall's static runs (``static/``): dry (the search's premise: it stands without
   water), then the water level at failure, the ``collapse`` analysis's search
   (drystone/analyses/ida.py, set to the study's grid: drystone/studies/common.py ``search_params``) over the
   level, one static run per step (``water.json``);
4. the PGA at collapse of every wall, site, record and polarity: one ``collapse`` analysis each
   (``searches/<name>/``), its search set to the study's grid up to the search's cap,
   bracketed to the wall's ``plan.tolerance``; several at once.

A wall the package refuses before any run (a CaseError) is left out and its refusal
reported. Finished runs with the same inputs are reused (every analysis is resumable), so an
interrupted study continues where it stopped; ``timing.json`` logs every invocation (elapsed
time, runs run and reused, the machine's load average).

Collapse of a seismic or static run: the package's one criterion (drystone/analyses/common.py
``outcome``: a stone fell, overturned or left the model; measured from the end of the gravity
stage, when the soil's load is fully on). Before the study ran on the analyses it read
collapse as the Sacsayhuaman paper does (studies/sacsayhuaman/analysis.py ``residuals``) and
bisected its own grids; docs/beyond-the-papers.md says which numbers came from which.
"""
from __future__ import annotations

import json
import os
import time
from pathlib import Path

from drystone import atomic
from drystone.studies import common as sc
from drystone.studies.site import plan as planmod

LABEL = "drystone/studies/site"


def surface_pga(out: Path) -> float | None:
    """The PGA at the surface (g) of a run with a site (spec.json's excitations), else None."""
    spec = sc.read_json(Path(out) / "spec.json") or {}
    for ex in spec.get("excitations", []):
        if ex.get("site"):
            return ex["site"].get("pga_surface_g")
    return None


def searches(cfg, walls=None) -> list[tuple[str, str, str, str]]:
    """(wall, site, record, polarity) of every search."""
    cfg = planmod.get(cfg)
    return [(w, s, r, pol) for w in (cfg.walls if walls is None else walls) for s in cfg.sites for r in cfg.records
            for pol in cfg.polarities[w]]


def tilt_wall(cfg, wall: str, backend="local", address=None, log=print) -> dict:
    from drystone.analyses import tilt

    case = planmod.WALLS[wall][2]
    return tilt.tilt(case, out=planmod.tilt_dir(cfg, wall), workers=1, backend=backend, address=address, log=log,
                     overrides=sc.quick_gravity(cfg.quick), **sc.tilt_protocol(case, cfg.quick))


def collapse_search(cfg, plan: dict, wall: str, site: str, record: str, polarity: str, backend="local",
                    address=None, log=print) -> dict:
    """One search's collapse analysis (collapse.json's dict)."""
    from drystone.analyses import collapse

    cap = plan["caps"][planmod.search_id(wall, site, record, polarity)]["cap_g"]
    return collapse.collapse(planmod.record_case(wall), [planmod.record_file(cfg, record, polarity)],
                             out=planmod.search_dir(cfg, wall, site, record, polarity), workers=1, backend=backend,
                             address=address, overrides=planmod.common_overrides(cfg) + planmod.site_overrides(site),
                             log=log, **sc.search_params(cap, planmod.tolerance(cfg, wall)),
                             stop_when_fallen=False)  # runs to their end: the published runs


def static_runs(cfg, backend="local", address=None, log=print) -> dict:
    """The retained wall dry, then the water level at which it fails (module docstring);
    writes and returns ``static/water.json``: {"dry": outcome, "water": search state or None}."""
    from drystone.analyses import common, ida

    root = planmod.static_dir(cfg)
    common.output_dir(planmod.STATIC_CASE, "static", root)
    kw = dict(common=planmod.static_common(cfg), workers=1, backend=backend, address=address, log=log)
    name = planmod.static_run_name(None)
    dry = dict(sc.run_row(common.run_jobs(planmod.STATIC_CASE, [(name, [])], root, "static-dry", **kw)[name],
                          root / "runs" / name), name=name)
    water = None
    if dry["status"] == "done" and not dry["collapsed"]:
        p = ida.Params(**sc.search_params(cfg.level_cap_m, cfg.level_resolution_m))
        observed, runs, status = {}, [], None
        for k in range(1, p.max_runs + 1):
            s = ida.step(observed, p)
            if s.done:
                break
            name = planmod.static_run_name(s.next_g)
            o = common.run_jobs(planmod.STATIC_CASE, [(name, planmod.static_overrides(s.next_g))], root,
                                f"water-{k:02d}", **kw)[name]
            runs.append(dict(o, name=name, level_m=s.next_g))
            if o["status"] != "done":
                status = "failed"
                break
            observed[s.next_g] = o["collapsed"]
        s = ida.step(observed, p)
        rec = {"status": status or s.status, "pga_at_collapse_g": s.bracket, "censored_at_g": s.censored_at_g,
               "standing_above_collapse_g": s.non_monotonic, "runs": runs}
        water = sc.search_state({"search": "water"}, rec, root)
    data = {"dry": dry, "water": water}
    atomic.write_text(root / "water.json", json.dumps(data, indent=1, default=str) + "\n")
    return data


def _log(m: str) -> None:
    print(m, flush=True)


def task(cfg, plan: dict, kind: str, key: tuple, backend="local", address=None) -> dict:
    """One piece of the study (``kind``: tilt of wall ``key[0]``, static of the retained wall,
    or search ``key`` = (wall, site, record, polarity)); returns {"failed": [runs], "refused":
    (wall, text) or None} (a module-level function: ``drystone.studies.in_parallel`` runs
    several at once)."""
    from drystone.model.case import CaseError

    wall = key[0]
    try:
        if kind == "tilt":
            t = tilt_wall(cfg, wall, backend, address, _log)
            failed = [f"tilt/{wall}/{d['run']}" for d in t["directions"].values() if d.get("status") == "failed"]
        elif kind == "static":
            d = static_runs(cfg, backend, address, _log)
            failed = [f"static/runs/{x['name']}" for x in [d["dry"]] + ((d["water"] or {}).get("runs") or [])
                      if x.get("status") != "done"]
        else:
            c = collapse_search(cfg, plan, *key, backend, address, _log)
            failed = [f"{planmod.search_name(*key)}/runs/{x['name']}" for rec in c["records"].values()
                      for x in rec["runs"] if x.get("status") != "done"]
    except CaseError as exc:
        if wall == "free":
            raise
        return {"failed": [], "refused": (wall, str(exc))}
    return {"failed": failed, "refused": None}


def run(config="full", workers=None, backend="local", address=None) -> dict:
    """Plan, tilt, static and water, and the seismic searches, several at once (module
    docstring). Returns {"rounds", "runs_run", "runs_reused", "failed", "interrupted",
    "refused", "elapsed_s", ...}."""
    from drystone.studies import in_parallel

    cfg = planmod.get(config)
    t0 = time.time()
    plan = planmod.build(cfg)
    refused, failed = {}, []
    summary = {"rounds": 0, "runs_run": 0, "runs_reused": 0, "interrupted": False, "refused": refused,
               "failed": failed, "workers": workers, "backend": backend, "cores": os.cpu_count(),
               "load_average_start": sc.load_average()}
    todo = [("tilt", (w,)) for w in cfg.walls if cfg.tilt]
    if "retained" in cfg.walls and cfg.water:
        todo.append(("static", ("retained",)))
    todo += [("search", k) for k in searches(cfg)]
    try:
        for res in in_parallel(task, [(cfg, plan, kind, key, backend, address) for kind, key in todo],
                               workers or os.cpu_count() or 1):
            failed += res["failed"]
            if res["refused"]:
                refused.setdefault(*res["refused"])
    except KeyboardInterrupt:
        summary["interrupted"] = True
    atomic.write_text(cfg.out_dir / "refused.json", json.dumps(refused, indent=1) + "\n")
    for w, why in refused.items():
        print(f"[site] wall {w} left out: {why}", flush=True)
    folders = ([planmod.tilt_dir(cfg, w) for w in cfg.walls] + [planmod.static_dir(cfg)]
               + [planmod.search_dir(cfg, *k) for k in searches(cfg)])
    summary["runs_run"], summary["runs_reused"], summary["rounds"] = sc.count_runs(folders, t0)
    return sc.finish(cfg.out_dir, summary, t0)
