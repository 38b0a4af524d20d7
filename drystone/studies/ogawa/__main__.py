"""python -m drystone.studies.ogawa study [--random N] [--runs R] [--substeps K]   1D friction studies
python -m drystone.studies.ogawa study3d [--workers N]   3D YADE model for the named sets (long; a resumable sweep)
python -m drystone.studies.ogawa refresh                 attach 3D results (named sets; the orientation / PGA / reset-vs-cumulative
                                        sweeps results/ogawa_pga, results/ogawa_cumulative), rewrite the report
python -m drystone.studies.ogawa insitu                  check Tables 1-2 averages, draw the Table 3 figure"""
from __future__ import annotations

import argparse
import json

from drystone.studies import exit_status
from drystone import paths


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="ogawa")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("study", help="friction studies with the 1D model (results/ogawa/)")
    s.add_argument("--random", type=int, default=50, help="number of random friction sets (50)")
    s.add_argument("--runs", type=int, default=5, help="successive runs of the record (5)")
    s.add_argument("--substeps", type=int, default=10, help="Newmark sub-steps per record sample (10: 1e-3 s)")
    s.add_argument("--workers", type=int, default=None)
    sub.add_parser("insitu", help="Tables 1-3: averages and figure")
    t = sub.add_parser("study3d", help="the 3D YADE model for the named friction sets (~4 min each)")
    t.add_argument("--workers", type=int, default=None)
    t.add_argument("--sets", nargs="*", default=None, help="named sets (default: all of ogawa.study.NAMED)")
    sub.add_parser("refresh", help="attach finished 3D runs (named sets, ogawa_pga and ogawa_cumulative sweeps) "
                                   "to results/ogawa/summary.json, rewrite the report")
    a = ap.parse_args(argv)
    if a.cmd == "study":
        from drystone.studies.ogawa import study
        summ = study.run(a.random, a.runs, a.substeps, workers=a.workers)
        print(json.dumps(summ["random_study"], indent=1))
        print(f"report: {study.OUT / 'report.md'}")
    elif a.cmd == "study3d":
        from drystone.studies.ogawa import study
        study.run_3d(a.sets or study.NAMED, workers=a.workers)
    elif a.cmd == "refresh":
        from drystone.studies.ogawa import study
        study.refresh()
    else:
        from drystone.studies.ogawa import insitu
        for q, site, mine, paper, ok in insitu.check_averages():
            print(f"{q:13s} {site:13s} recomputed {mine:8.4f}  paper {paper:6.2f}  {'ok' if ok else 'DIFFERS'}")
        print(insitu.figure(paths.RESULTS / "ogawa" / "friction_vs_roughness.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(exit_status(main()))
