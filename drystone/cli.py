"""Command line: python -m drystone {run, report, sweep, keys, layout, compare, bench, free-decay} and the
analyses of any case (drystone/analyses: tilt, modal, collapse, fragility, limit, assess)."""
from __future__ import annotations

import argparse
import json
import os
import signal
import sys
from pathlib import Path

from drystone import atomic
from drystone.model import case as casemod


def interrupt_on_sigterm() -> None:
    """SIGTERM (kill, a scheduler ending a job) stops a run or sweep like Ctrl-C: YADE
    processes are killed, finished runs recorded, exit 130 (python -m drystone)."""
    def _interrupt(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, _interrupt)


def _add_analyses(sub) -> dict:
    """One subcommand per analysis of drystone/analyses (REGISTRY) whose module is present:
    name -> module (``add_arguments``, ``main``)."""
    from drystone import analyses

    mods = analyses.available()
    for name, mod in mods.items():
        mod.add_arguments(sub.add_parser(name, help=mod.HELP, description=mod.__doc__,
                                         formatter_class=argparse.RawDescriptionHelpFormatter))
    return mods


def main(argv=None) -> int:
    import drystone

    ap = argparse.ArgumentParser(prog="drystone", description=__doc__)
    ap.add_argument("--version", action="version", version=f"drystone {drystone.__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run a case file")
    r.add_argument("case")
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case key, e.g. --set contact.law=stock_volumetric")
    r.add_argument("--out", help="output folder (default results/<case name>)")
    r.add_argument("-j", "--threads", type=int, default=1)
    r.add_argument("--engine", choices=("compiled", "python"), default="compiled",
                   help="step engine of the project's law (compiled: numba, default; python: numpy law with "
                        "YADE's integrator, the reference)")
    r.add_argument("-q", "--quiet", action="store_true")
    r.add_argument("--json", action="store_true",
                   help="print the summary's penetration, slip and collapse-angle keys as JSON (machine output) "
                        "instead of the summary lines")
    k = sub.add_parser("keys", help="print the table of case-file keys (Markdown)")
    k.add_argument("--update-docs", "--update-readme", dest="update_docs", action="store_true",
                   help="write the table into docs/case-keys.md (--update-readme: the old name)")
    lay = sub.add_parser("layout", help="print the table of the package's layers (Markdown)")
    lay.add_argument("--update-docs", "--update-readme", dest="update_docs", action="store_true",
                     help="write the table into docs/maintainers-guide.md (--update-readme: the old name)")
    c = sub.add_parser("compare", help="compare finished verification runs with the paper")
    c.add_argument("folders", nargs="+")
    b = sub.add_parser("bench", help="speed figures: 40-block wall, 500/2000-stone walls, threads, Sacsayhuaman")
    b.add_argument("--only", nargs="+", choices=("running_bond", "scale", "threads", "sacsayhuaman", "limit",
                                                 "fragility_ida", "compile", "profile"),
                   help="run only these sections (bench.json keeps the others' earlier figures)")
    b.add_argument("--sizes", nargs="+", type=int, choices=(40, 500, 2000), default=[40, 500, 2000],
                   help="scale section: wall sizes (stones, about)")
    walls = ("running_bond", "irregular", "polygonal")  # drystone.bench.WALLS (not imported here: a quick CLI)
    b.add_argument("--walls", nargs="+", choices=walls, default=list(walls),
                   help="scale section: wall kinds (polygonal: 500 stones only)")
    b.add_argument("--steps", type=int, default=300, help="scale section: steps per run (300)")
    b.add_argument("--engines", nargs="+", choices=("compiled", "python"), default=None,
                   help="scale section: step engines (default: the runner's default)")
    b.add_argument("--records", type=int, default=None,
                   help="fragility_ida section: the first N FEMA P695 far-field records (default all 22)")
    b.add_argument("--tolerance", type=float, default=None, help="fragility_ida section: IDA bracket width, g (0.1)")
    b.add_argument("--duration", type=float, default=None,
                   help="fragility_ida section: S seconds of each record from 1 s before its peak (default whole)")
    b.add_argument("--workers", type=int, default=2, help="fragility_ida section: parallel runs (2)")
    b.add_argument("--baseline", metavar="COMMIT", default=None,
                   help="also run COMMIT's scale section (a git worktree) and this tree's back to back, "
                        "alternating, for --walls and --sizes: both ms/step and the speed-up (alone without --only)")
    b.add_argument("--rounds", type=int, default=2, help="--baseline: alternating rounds (2)")
    sub.add_parser("free-decay", help="damping ratio per mode of one block (both contact geometries) and rocking "
                   "restitution per impact against Housner's -> "
                   "results/free_decay/report.md")
    w = sub.add_parser("sweep", help="run a sweep file (many overrides of one case) in parallel, resumably")
    w.add_argument("sweep")
    w.add_argument("--workers", type=int, default=None, help="parallel runs (default: number of cores)")
    w.add_argument("--backend", choices=("local", "dask"), default="local")
    w.add_argument("--dask", metavar="ADDRESS", default=None,
                   help="Dask scheduler address (tcp://host:8786); 'local' starts a LocalCluster (implies --backend dask)")
    w.add_argument("--only", nargs="*", default=None, metavar="RUN", help="run only these runs of the sweep")
    w.add_argument("-j", "--threads", type=int, default=1, help="YADE threads per run (1)")
    rep = sub.add_parser("report", help="write RUN_DIR/report.html: one self-contained page of a finished run "
                         "(a study's folder: its report.md as report.html)")
    rep.add_argument("run_dir", metavar="RUN_DIR")
    analyses = _add_analyses(sub)
    a = ap.parse_args(argv)
    try:
        if a.cmd in analyses:
            return int(analyses[a.cmd].main(a) or 0)
        if a.cmd == "run":
            from drystone import runner
            s = runner.run(a.case, a.set, a.out, a.threads, a.quiet, engine=a.engine)
            if not a.json:  # the summary lines by kind of run (drystone/postprocess/console.py)
                from drystone import paths
                from drystone.postprocess import console
                out = Path(a.out).expanduser().resolve() if a.out else paths.RESULTS / s["name"]
                spec = json.loads((out / "spec.json").read_text())
                print("\n".join(console.lines(s, spec, out)))
                return 0
            keys = [k for k in s if k.startswith(("penetration", "slip", "collapse_angle"))]
            print(json.dumps({k: s[k] for k in keys}, indent=1))
            left = (s.get("run") or {}).get("left_model") or {}
            if left.get("count"):
                print(f"warning: {left['count']} of {left['free_blocks']} free block(s) left the model "
                      f"({', '.join(str(b['block']) for b in left['blocks'][:10])}): their motion is unbounded "
                      "and has no residual (summary.json run.left_model)", file=sys.stderr)
        elif a.cmd in ("keys", "layout"):
            from drystone import layers
            from drystone import paths
            table, into_doc, p = ((casemod.describe, casemod.readme_with_keys, paths.DOCS / "case-keys.md")
                                  if a.cmd == "keys" else
                                  (layers.readme_block, layers.readme_with_layout, paths.DOCS / "maintainers-guide.md"))
            if a.update_docs:
                atomic.write_text(p, into_doc(p.read_text()))
                print(f"updated {p}")
            else:
                print(table())
        elif a.cmd == "compare":
            from drystone.postprocess import compare
            print(compare.report(a.folders))
        elif a.cmd == "sweep":
            from drystone import sweep
            backend = "dask" if a.dask else a.backend
            res = sweep.run(a.sweep, a.workers, backend, a.dask, a.threads, a.only)
            return 130 if res["interrupted"] else 1 if res["failed"] else 0
        elif a.cmd == "report":
            from drystone.postprocess import report
            try:
                print(report.write(a.run_dir))
            except report.NotARun as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 2
        elif a.cmd == "free-decay":
            from drystone.analyses import free_decay
            print(free_decay.report().read_text())
        elif a.cmd == "bench":
            from drystone import bench
            frag = {"n_records": a.records, "duration_s": a.duration, "workers": a.workers,
                    **({"tolerance": a.tolerance} if a.tolerance is not None else {})}
            from drystone.bench_baseline import BaselineError
            if a.rounds < 1:
                print(f"error: bench --rounds: {a.rounds} (at least 1)", file=sys.stderr)
                return 2
            try:
                bench.main(a.only, a.sizes, a.walls, a.steps, a.engines, frag, a.baseline, a.rounds)
            except BaselineError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 2
    except KeyboardInterrupt:
        print("interrupted: the results folder is unchanged", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `drystone keys | head`: the reader left; say nothing more
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except casemod.CaseError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except Exception as exc:  # noqa: BLE001 - report any failure clearly and exit non-zero
        from drystone.runner import RunError
        from drystone.geometry.blockfile import GeometryError
        if isinstance(exc, (RunError, GeometryError)):
            print(f"error: {exc}", file=sys.stderr)
            return 2
        if isinstance(exc, OSError):  # a disk full, a read-only or missing folder: the system's words
            print(f"error: {exc.filename or ''}{': ' if exc.filename else ''}{exc.strerror or exc}", file=sys.stderr)
            return 2
        raise
    return 0
