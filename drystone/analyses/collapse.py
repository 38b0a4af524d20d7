"""PGA at collapse of any case under each of several records, by incremental dynamic
analysis (IDA): ``python -m drystone collapse CASE --record FILE|NAME ... [--tolerance
0.05] [--cap 3.0] [--stage NAME]``.

Each record replaces the record of the case's one excitation stage (or ``--stage``;
without ``--record``, the case's own motion of that stage, a record, sine or white noise;
a case without an excitation stage is shaken by each record along ``--direction`` after
its own stages, then rests until the motion has died out, common.py ``REST``) and is scaled
to a sequence of PGAs (g) chosen by hunt-and-fill (drystone/analyses/ida.py:
geometric hunt up from ``--start``, bracketing of the lowest collapse to ``--tolerance``,
fill-in below it; a collapse below a level that stood, a non-monotonic response, is
detected, reported and the lowest collapse kept; a wall standing at ``--cap`` is censored
there). Collapse is the package's one criterion (drystone/analyses/common.py ``outcome``).
The searches of all records advance together, one round of runs at a time (one run per
open record, or ``--probes`` runs: a sweep, so finished runs are reused when the analysis is run again and the
rounds can go to a Dask cluster).

Writes into results/<case name>/collapse/ (or ``--out``): ``collapse.json``
(``records``: {record stem: {"pga_at_collapse_g": [lo, hi] or null, "censored_at_g",
"runs": [...], "non_monotonic", "standing_above_collapse_g", "status"}}, with the
criterion, the search's parameters, the cost and the provenance), ``ida.png`` (the IDA
curves: largest residual displacement against PGA, one curve per record, collapses
marked) and ``report.html``; the runs in ``runs/<record stem>-pga_<g>/``.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from drystone.analyses import common, ida

HELP = "PGA at collapse per record by incremental dynamic analysis (hunt-and-fill) -> collapse.json, report.html"

#: the longest a collapse analysis may go on (rounds of runs); a search ends well before (``ida.Params.max_runs``)
MAX_ROUNDS = 100


def add_arguments(p) -> None:
    common.add_common_arguments(p)
    p.add_argument("--record", nargs="+", action="extend", default=[], metavar="FILE|NAME|fema:ID",
                   help="acceleration record(s): a file, a catalogue name (docs/motions.md) or a FEMA P695 id such "
                        "as fema:12a (ASSUMED stand-in); repeatable "
                        "(default: the case's own excitation, scaled)")
    p.add_argument("--tolerance", type=float, default=0.05, help="final bracket width, g (0.05)")
    p.add_argument("--cap", type=float, default=3.0, help="highest PGA run, g: a wall standing there is censored (3.0)")
    p.add_argument("--start", type=float, default=0.1, help="first PGA of the hunt, g (0.1)")
    p.add_argument("--factor", type=float, default=2.0, help="hunt-up factor between levels (2)")
    p.add_argument("--fill", type=float, default=0.25,
                   help="fill in below the collapse until no gap exceeds this fraction of it (0.25; 0: no fill-in)")
    p.add_argument("--max-runs", type=int, default=30, help="most runs per record (30)")
    p.add_argument("--full-runs", action="store_true",
                   help="run every run to its end (default: a run stops once a stone fell or left the model, "
                        "output.stop_when_fallen)")
    p.add_argument("--probes", type=int, default=1,
                   help="PGAs of one record run at once, each round (1; e.g. the cores per record: fewer rounds, "
                        "a few more runs; drystone/analyses/ida.py plan)")
    p.add_argument("--stage", default=None, help="the excitation stage whose record is replaced (name or index), "
                   "when the case has several")
    p.add_argument("--direction", choices=("x", "y"), default="y",
                   help="for a case without an excitation stage: the records shake it along this axis, after its own "
                        "stages, then it rests until the motion dies out (y: out of plane, the default)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case key in every run (as drystone run --set)")


def main(args) -> int:
    backend, address = common.backend_of(args)
    res = collapse(args.case, args.record, tolerance=args.tolerance, cap=args.cap, stage=args.stage, out=args.out,
                   workers=args.workers, backend=backend, address=address, start=args.start, factor=args.factor,
                   fill=args.fill or None, max_runs=args.max_runs, overrides=args.set,
                   direction=args.direction, probes=args.probes, stop_when_fallen=not args.full_runs)
    for stem, r in res["records"].items():
        print(f"{stem}: {describe(r)}")
    print(f"report: {Path(res['out_dir']) / 'report.html'}")
    return 1 if any(r["status"] == "failed" for r in res["records"].values()) else 0


def describe(r: dict) -> str:
    """One line: a record's PGA at collapse."""
    if r["status"] == "failed":
        return f"failed ({r.get('error', '')})"
    if r["pga_at_collapse_g"]:
        lo, hi = r["pga_at_collapse_g"]
        txt = f"PGA at collapse in ({lo:g}, {hi:g}] g"
    elif r["censored_at_g"] is not None:
        txt = f"no collapse up to the cap, {r['censored_at_g']:g} g (censored)"
    else:
        txt = "no bracket"
    if r["status"] == "budget":
        txt += " (stopped at the run budget; bracket not final)"
    if r["non_monotonic"]:
        txt += f"; non-monotonic: standing at {', '.join(f'{g:g}' for g in r['standing_above_collapse_g'])} g"
    return f"{txt}; {len(r['runs'])} run(s)"


def _records(case_path, case_dict, records, stage, direction, overrides) -> tuple[dict, int]:
    """(record stem -> (record as given, its overrides), index of the excitation stage);
    one-line errors before any run. A case without an excitation stage is shaken by each
    record along ``direction`` after its own stages (common.py ``shaking_override``)."""
    where = str(case_path)
    has = any(st.get("type") == "excitation" for st in case_dict["stages"])
    if not records:  # the case's own motion, scaled
        if not has and stage is None:
            raise common.casemod.CaseError(f"{where}: the case has no excitation stage: give --record FILE|NAME "
                                           "(it is then added, after the case's own stages)")
        k = common.excitation_stage(case_dict, stage, where)
        st = case_dict["stages"][k]
        m = st["motion"]
        stem = (common.safe_name(st["record"]) if m == "record" else
                f"sine_{common.number_tag(st['frequency_hz'])}hz" if m == "sine" else m)
        return {stem: (f"the case's own {m}" + (f" ({st['record']})" if m == "record" else ""), [])}, k
    k = None if not has and stage is None else common.excitation_stage(case_dict, stage, where)
    out = {}
    for r in records:
        stem = common.safe_name(r)
        if stem in out:
            raise common.casemod.CaseError(f"{where}: two records named {stem!r} ({out[stem][0]!r} and {r!r}): "
                                           "rename one file")
        if k is None:
            over, kk = common.shaking_override(case_path, r, direction, overrides)
        else:
            over, kk = common.record_override(case_dict, r, stage, where), k
        out[stem] = (str(r), over)
    return out, kk


def collapse(case, records, tolerance: float = 0.05, cap: float = 3.0, stage=None, out=None, workers=None,
             backend: str = "local", address=None, start: float = 0.1, factor: float = 2.0,
             fill: float | None = 0.25, max_runs: int = 30, overrides=(), direction: str = "y",
             probes: int = 1, stop_when_fallen: bool = True, log=print) -> dict:
    """The PGA at collapse of ``case`` under each of ``records`` (module docstring);
    returns what it writes to collapse.json, with ``out_dir``. ``stop_when_fallen``: each run
    stops once a stone is certain to have collapsed (case key output.stop_when_fallen: it
    fell or left the model; the run's outcome is then decided)."""
    from drystone.model import case as casemod

    t0 = time.time()
    case_path = Path(case).resolve()
    case_dict = casemod.load(case_path, list(overrides))
    try:
        params = ida.Params(start=start, factor=factor, cap=cap, tolerance=tolerance, fill=fill,
                            max_runs=max_runs).check()
    except ValueError as exc:
        raise casemod.CaseError(f"{case}: {exc}") from None
    recs, k = _records(case_path, case_dict, records, stage, direction, overrides)
    out_dir = common.output_dir(case_path, "collapse", out)
    if probes < 1:
        raise casemod.CaseError(f"{case}: --probes must be >= 1, got {probes!r}")
    observed = {stem: {} for stem in recs}
    results = {stem: [] for stem in recs}
    failed = {}
    n_runs = 0
    for rnd in range(1, MAX_ROUNDS + 1):
        todo = []
        for stem, (_, over) in recs.items():
            if stem in failed:
                continue
            for g in ida.plan(observed[stem], params, probes):
                name = f"{stem}-pga_{common.number_tag(g)}"
                todo.append((stem, g, name, over + [f"stages.{k}.pga_g={g!r}"]
                             + (["output.stop_when_fallen=true"] if stop_when_fallen else [])))
        if not todo:
            break
        log(f"[collapse] round {rnd}: {len(todo)} run(s) ({', '.join(n for _, _, n, _ in todo)}); "
            f"{n_runs} run so far")
        res = common.run_jobs(case_path, [(n, o) for _, _, n, o in todo], out_dir, f"round-{rnd:02d}",
                              list(overrides), workers, backend, address, log)
        for stem, g, name, _ in todo:
            o = res[name]
            n_runs += 1
            results[stem].append(dict(_row(o), pga_g=g, name=name))
            if o["status"] != "done":
                failed[stem] = o.get("error", "")
            else:
                observed[stem][g] = o["collapsed"]
    summary = {}
    for stem, (given, _) in recs.items():
        s = ida.step(observed[stem], params)
        rows = sorted(results[stem], key=lambda r: r["pga_g"])
        r = {"record": given, "status": "failed" if stem in failed else s.status,
             "pga_at_collapse_g": s.bracket if s.high_g is not None and s.status in ("bracketed", "budget") else None,
             "censored_at_g": s.censored_at_g, "non_monotonic": bool(s.non_monotonic),
             "standing_above_collapse_g": list(s.non_monotonic), "runs": rows}
        if stem in failed:
            r["error"] = failed[stem]
        note = record_note(given)
        if note:
            r["note"] = note
        summary[stem] = r
    wall = [r.get("wall_s") or 0.0 for rs in results.values() for r in rs]
    data = {"analysis": "collapse", "case": str(case_path), "overrides": list(overrides),
            "stage": k, "direction_if_added": direction,
            "intensity": "pga_g (g) of the excitation stage's motion, as scaled by the stage's pga_g",
            "criterion": common.CRITERION,
            "search": {"method": "hunt-and-fill (drystone/analyses/ida.py)", "start_g": start, "factor": factor,
                       "cap_g": cap, "tolerance_g": tolerance, "fill": fill, "max_runs": max_runs,
                       "probes": probes, "stop_when_fallen": bool(stop_when_fallen)},
            "records": summary,
            "cost": {"runs": n_runs, "run_wall_s": sum(wall), "elapsed_s": time.time() - t0}}
    common.write_json(out_dir / "collapse.json", data, case=case_path, overrides=overrides)
    fig = ida_figure(summary, out_dir / "ida.png")
    common.write_report(out_dir, f"PGA at collapse: {case_path.name}", report_markdown(data), [fig])
    return dict(data, out_dir=str(out_dir))


def record_note(given: str) -> str | None:
    """For a FEMA P695 id (as given, or the case's own): its event and station, labelled ASSUMED."""
    from drystone.motions import fema

    ids = [w.strip("()") for w in str(given).split() if fema.parse_id(w.strip("()"))]
    if not ids:
        return None
    c = fema.entry(ids[0])
    return (f"{fema.canonical_id(c)}: FEMA P695 {c['set']} {c['record_id']}{c['component']}, {c['event']} "
            f"{c['year']}, {c['station']}; {fema.ASSUMED}")


def _row(o: dict) -> dict:
    keys = ("status", "collapsed", "collapsed_stones", "why", "left_model", "largest_residual_m",
            "largest_residual_stone", "largest_out_of_plane_m", "in_plane_sliding", "settled", "end_time_s", "wall_s",
            "error")
    return {k: o.get(k) for k in keys if k in o}


def ida_figure(records: dict, path: Path) -> Path:
    """IDA curves: largest residual displacement (mm) of the stones still in the model
    against PGA (g), one curve per record; a run that collapsed the wall is an x at the top."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    stood = [1e3 * r["largest_residual_m"] for rec in records.values() for r in rec["runs"]
             if r.get("status") == "done" and not r.get("collapsed") and r.get("largest_residual_m") is not None]
    top = 1.2 * max(stood) if stood and max(stood) > 0 else 1.0
    for stem, rec in records.items():
        runs = [r for r in rec["runs"] if r.get("status") == "done"]
        xs = [r["pga_g"] for r in runs]
        ys = [top if r["collapsed"] else 1e3 * r["largest_residual_m"] for r in runs]
        line, = ax.plot(xs, ys, "-o", ms=4, label=stem)
        cx = [r["pga_g"] for r in runs if r["collapsed"]]
        ax.plot(cx, [top] * len(cx), "x", ms=9, mew=2, color=line.get_color())
    ax.axhline(top, color="0.6", lw=0.8, ls=":")
    ax.text(0.01, top, " collapsed (x)", va="bottom", fontsize=8, transform=ax.get_yaxis_transform())
    ax.set_xlabel("PGA (g)")
    ax.set_ylabel("largest residual displacement (mm)")
    ax.set_ylim(0, top * 1.1)
    ax.set_xlim(left=0)
    ax.grid(alpha=0.3)
    if records:
        ax.legend(fontsize=8)
    fig.tight_layout()
    from drystone import atomic

    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def report_markdown(data: dict) -> str:
    s = data["search"]
    L = [f"# PGA at collapse: {Path(data['case']).name}", "",
         f"Case `{data['case']}`; the motion of stage {data['stage']} (each record below in turn) scaled to PGAs "
         f"chosen by hunt-and-fill (start {s['start_g']:g} g, x{s['factor']:g}, bracket to {s['tolerance_g']:g} g, "
         f"fill-in {s['fill'] or 'none'}, cap {s['cap_g']:g} g).", "",
         f"Collapse: {data['criterion']}.", "",
         "| record | PGA at collapse (g) | runs | non-monotonic | status |", "|---|---|---|---|---|"]
    for stem, r in data["records"].items():
        b = r["pga_at_collapse_g"]
        pga = f"({b[0]:g}, {b[1]:g}]" if b else (f"> {r['censored_at_g']:g} (censored)" if r["censored_at_g"]
                                                 is not None else "-")
        nm = ("standing at " + ", ".join(f"{g:g}" for g in r["standing_above_collapse_g"])
              if r["non_monotonic"] else "no")
        L.append(f"| {stem} | {pga} | {len(r['runs'])} | {nm} | {r['status']} |")
    notes = [r["note"] for r in data["records"].values() if r.get("note")]
    if notes:
        L += [""] + [f"- {n}" for n in notes]
    L += ["", "![IDA curves](ida.png)", "", "## Runs", "",
          "| record | PGA (g) | collapsed | stones | largest residual (mm) | in-plane sliding | run |",
          "|---|---|---|---|---|---|---|"]
    for stem, r in data["records"].items():
        for x in r["runs"]:
            res = x.get("largest_residual_m")
            L.append(f"| {stem} | {x['pga_g']:g} | {x.get('collapsed', x.get('status'))} | "
                     f"{' '.join(map(str, x.get('collapsed_stones') or [])) or '-'} | "
                     f"{'-' if res is None else f'{1e3 * res:.1f}'} | "
                     f"{' '.join(map(str, x.get('in_plane_sliding') or [])) or '-'} | `runs/{x['name']}` |")
    c = data["cost"]
    L += ["", f"Cost: {c['runs']} run(s), {c['run_wall_s'] / 60:.1f} run-minutes, "
              f"{c['elapsed_s'] / 60:.1f} min elapsed."]
    return "\n".join(L) + "\n"


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: python -m drystone collapse CASE --record ...")
