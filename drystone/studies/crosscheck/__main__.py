"""``python -m drystone.studies.crosscheck {small,all,report}``: the LMGC90 cross-check (issue 15, item 2).

* ``small``: the toppling block and the half-sine pulse: LMGC90 (at its step and half of
  it), the closed forms, this package at K_n = 2e8 x 1, 10, 100 (~4 min on a quiet
  2-core machine); then the report.
* ``all``: ``small`` plus the 40-block running-bond wall and the Santa-Cruz tilt walls
  (seeds 0-4; long: see results/crosscheck/report.md for the cost of each run).
* ``report``: rewrite results/crosscheck/report.md and figures from crosscheck.json.

Where compas_lmgc90 (pinned in requirements-crosscheck.txt) is not importable, ``small``
and ``all`` print one "crosscheck skipped: ..." line saying which package and version is
missing and how to install it, and exit 0.
"""
from __future__ import annotations

import argparse
import sys
import time

from drystone.studies import exit_status
from drystone.studies.crosscheck import cases, lmgc90_status


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drystone.studies.crosscheck", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=("small", "all", "report"))
    ap.add_argument("--cases", nargs="+", choices=sorted(cases.CASES), help="only these cases")
    ap.add_argument("--kn-factors", nargs="+", type=float, help="K_n = 2e8 x these for the package side "
                    "(default: per case, 1 10 100 for the small cases)")
    ap.add_argument("--seeds", nargs="+", type=int, help="tilt_wall seeds (default 0-4)")
    ap.add_argument("--no-package", action="store_true", help="LMGC90 and closed forms only (keeps the package "
                    "runs already in crosscheck.json)")
    ap.add_argument("--no-lmgc90", action="store_true", help="the package only, at --kn-factors (keeps LMGC90's run "
                    "and the package runs at other K_n already in crosscheck.json)")
    ap.add_argument("--out", help="output folder (default results/crosscheck)")
    args = ap.parse_args(argv)

    if args.mode != "report":
        ok, msg = lmgc90_status()  # first: nothing else is needed to say it is missing
        if not ok:
            print(f"crosscheck skipped: {msg}")
            return 0
    from drystone.studies.crosscheck import report, study

    out = study.OUT if args.out is None else args.out
    if args.mode == "report":
        data = study.load(out)
        if not data["cases"]:
            ok, msg = lmgc90_status()
            print(f"crosscheck report: no results in {out} yet" + ("" if ok else f" (crosscheck skipped: {msg})"))
            return 0
        print(f"crosscheck report: {report.write(out)}")
        return 0
    names = args.cases or (list(cases.SMALL) if args.mode == "small" else list(cases.CASES))
    t0 = time.time()
    for name in names:
        variants = tuple(args.seeds) if (name == "tilt_wall" and args.seeds) else None
        study.run_case(name, out, kn_factors=args.kn_factors, variants=variants, package_side=not args.no_package,
                       lmgc90_side=not args.no_lmgc90)
    path = report.write(out)
    print(f"crosscheck: {', '.join(names)} in {time.time() - t0:.0f} s; report {path}")
    return 0


if __name__ == "__main__":
    sys.exit(exit_status(main()))
