"""python -m drystone.studies.fragility {plan,run,fit,report,all} [--workers N] [--dask ADDRESS] [--config small|full]

plan     FEMA P695 far-field records (component a out of plane) x PGA stripes 0.1-1.0 g with per-run
         draws of mu and K_n -> results/fragility/plan.json (the records in stripes/records/)
run      plan, then the fragility analysis of cases/sacsayhuaman/record.toml, --method stripes, with those
         draws -> results/fragility/stripes/ (resumable: finished runs are reused; local pool or Dask)
fit      damage states of the finished runs, lognormal fragility curves in PGA (default), PGV and Sa(T1)
         -> fragility.json, runs.csv
report   fit, then fragility.png and report.md
all      run, then report
--config small: 2 records x 2 stripes, records cut to 2 s (results/fragility_small/): a pipeline check."""
from __future__ import annotations

import argparse
import json

from drystone.studies import exit_status
from drystone.studies.fragility import plan as planmod
from drystone.studies.fragility import study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.studies.fragility", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("plan", "run", "fit", "report", "all"))
    ap.add_argument("--workers", type=int, default=None, help="parallel runs (default: cores)")
    ap.add_argument("--dask", metavar="ADDRESS", default=None, help="Dask scheduler address, or 'local'")
    ap.add_argument("--config", choices=tuple(planmod.CONFIGS), default="full")
    a = ap.parse_args(argv)
    kw = {"workers": a.workers, "backend": "dask" if a.dask else "local", "address": a.dask}
    cfg = planmod.get(a.config)
    if a.step == "plan":
        path = study.plan(cfg)
        p = planmod.load_plan(path.parent)
        print(f"{path}: {len(p['records'])} records x {len(cfg.stripes_g)} stripes = {len(p['runs'])} runs "
              f"(records in {planmod.analysis_dir(path.parent) / 'records'})")
        return 0
    if a.step == "run":
        r = study.run(cfg, **kw)
        return 1 if r["failed"] or r["interrupted"] else 0
    if a.step == "all":
        r = study.run(cfg, **kw)
        if r["interrupted"]:
            return 130
    if a.step == "fit":
        d = study.fit_step(cfg)
        for n, e in d["fits"].items():
            f = e["fit"]
            print(f"{n}: " + (f"theta {f['theta']:.3g} g, beta {f['beta']:.3g}" if f else f"no fit: {e['reason']}"))
        im = d["intensity_measures"]
        for m in im["measures"]:
            for n, e in im["fits"][m["key"]].items():
                f = e["fit"]
                print(f"{n} in {m['symbol']} ({m['unit']}): "
                      + (f"theta {f['theta']:.3g}, beta {f['beta']:.3g}" if f else "no fit"))
        print("smallest beta: " + ", ".join(f"{n} {v or '-'}" for n, v in im["most_efficient"].items()))
        print(json.dumps(d["runs"]))
        return 0
    path = study.report(cfg)
    print(path.read_text())
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(exit_status(main()))
