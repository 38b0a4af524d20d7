"""python -m drystone.studies.shape {plan,run,report,all} [--config full|small] [--workers N] [--dask ADDRESS]

plan     the four walls x seeds (results/<out>/geometry/), the records' strong-motion windows
         (results/shape/records/) and the tilt sweep file -> results/<out>/plan.json
run      plan, the tilt sweep, then bisection rounds of the PGA at collapse (one sweep file per round,
         results/<out>/rounds/; resumable: finished runs are skipped; local pool or Dask)
report   every search replayed from the runs on disk -> shape.json, runs.csv, shape.png, report.md
all      run, then report
--config small: 2 variants, 1 seed, 1 record cut to 3 s, a 1.6 g bracket (results/shape_small/): a
pipeline check, not a result."""
from __future__ import annotations

import argparse

from drystone.studies.shape import plan as planmod
from drystone.studies.shape import study


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.studies.shape", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("step", choices=("plan", "run", "report", "all"))
    ap.add_argument("--config", choices=tuple(planmod.CONFIGS), default="full")
    ap.add_argument("--workers", type=int, default=None, help="parallel runs (default: cores)")
    ap.add_argument("--dask", metavar="ADDRESS", default=None, help="Dask scheduler address, or 'local'")
    a = ap.parse_args(argv)
    cfg = planmod.get(a.config)
    kw = {"workers": a.workers, "backend": "dask" if a.dask else "local", "address": a.dask}
    if a.step == "plan":
        p = planmod.build(cfg)
        print(f"{cfg.out_dir / 'plan.json'}: {len(p['geometries'])} walls, records {', '.join(p['records'])}")
        return 0
    if a.step in ("run", "all"):
        r = study.run(cfg, **kw)
        print(f"[shape] {r['rounds']} round(s), {r['runs_run']} run(s) run, {r['runs_reused']} reused, "
              f"{len(r['failed'])} failed, {r['elapsed_s'] / 60:.1f} min")
        if r["interrupted"]:
            return 130
        if a.step == "run":
            return 1 if r["failed"] else 0
    path = study.report(cfg)
    print(path.read_text())
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
