"""The one command for a wall: ``python -m drystone assess CASE [--quick]``.

Runs, into results/<case name>/assess/ (or ``--out``), one folder each:

1. ``tilt/``: the collapse angle tilting towards +y (drystone/analyses/tilt.py), beside the
   rigid-block limit angle of the wall as built (both frictions; ``parts.tilt.limit``);
2. ``modal/``: frequencies and mode shapes, when the modal analysis is present
   (drystone/analyses/modal.py; skipped, and said so, otherwise);
3. ``fragility/``: the PGA at collapse under a small default record set by IDA
   (``fragility/collapse/``, drystone/analyses/collapse.py) and the lognormal fragility of
   collapse, DS1 and DS2 from those runs (drystone/analyses/fragility.py).

``assess.json`` gathers the headline numbers and the cost (runs, core-minutes: the
runs' own wall time summed), ``report.html`` joins them with links to each report.

Records (``DEFAULT_RECORDS``, FEMA P695 far field, ASSUMED stand-ins): six records;
``--quick``: three of them cut to ``QUICK["duration_s"]`` s around their peak, a coarse bracket,
a low cap and a faster tilt (``QUICK``): a first look in minutes, not a result.
"""
from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

from drystone.analyses import common

HELP = "tilt, modal, PGA at collapse and fragility of a wall in one report -> assess.json, report.html"

#: FEMA P695 far-field records 1, 3, 5, 7, 9, 11, component a (ASSUMED stand-ins for any site's records;
#: their events and stations are in the reports)
DEFAULT_RECORDS = ("fema:1a", "fema:3a", "fema:5a", "fema:7a", "fema:9a", "fema:11a")
#: the full assessment's search
FULL = {"records": DEFAULT_RECORDS, "duration_s": None, "start": 0.1, "factor": 2.0, "cap": 2.0, "tolerance": 0.05,
        "fill": 0.25, "max_runs": 20, "tilt_rate": 1.0, "n_boot": 1000}
#: --quick: a first look (short records, coarse bracket, low cap, faster tilt)
QUICK = {"records": DEFAULT_RECORDS[:3], "duration_s": 4.0, "start": 0.3, "factor": 2.0, "cap": 2.4,
         "tolerance": 0.3, "fill": None, "max_runs": 6, "tilt_rate": 5.0, "n_boot": 200}


def add_arguments(p) -> None:
    common.add_common_arguments(p)
    p.add_argument("--quick", action="store_true", help="a first look in minutes: short records, coarse search")
    p.add_argument("--records", nargs="+", default=None, metavar="farfield|FILE|NAME|fema:ID",
                   help=f"records for the IDA (default {' '.join(DEFAULT_RECORDS)}; --quick: the first 3)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a case key in every run")


def main(args) -> int:
    backend, address = common.backend_of(args)
    res = assess(args.case, quick=args.quick, records=args.records, out=args.out, workers=args.workers,
                 backend=backend, address=address, overrides=args.set)
    for line in res["summary"]:
        print(line)
    print(f"report: {Path(res['out_dir']) / 'report.html'}")
    return 0


def assess(case, quick: bool = False, records=None, out=None, workers=None, backend: str = "local", address=None,
           overrides=(), log=print) -> dict:
    """Tilt, modal (when present), collapse and fragility of ``case``; returns assess.json's
    content with ``out_dir``."""
    from drystone.analyses import fragility as fragmod
    from drystone.analyses import tilt as tiltmod

    t0 = time.time()
    case_path = Path(case).resolve()
    common.case_name(case_path)  # a bad case: its one-line error before any run
    cfg = dict(QUICK if quick else FULL)
    if records:
        cfg["records"] = tuple(records)
    out_dir = common.output_dir(case_path, "assess", out)
    parts, summary, runs, run_s = {}, [], 0, 0.0

    log("[assess] 1/3 tilt towards +y")
    t = tiltmod.tilt(case_path, towards=("+y",), out=out_dir / "tilt", workers=workers, backend=backend,
                     address=address, rate=cfg["tilt_rate"], overrides=overrides, log=log)
    d = t["directions"]["+y"]
    parts["tilt"] = {"report": "tilt/report.html", "headline_deg": d.get("headline_deg"),
                     "criterion": d.get("criterion"), "reached": d.get("reached"), "rate_deg_s": cfg["tilt_rate"],
                     "reaction_drop_deg": d.get("reaction_drop_deg"), "limit": d.get("limit")}
    runs += 1
    run_s += _tilt_wall(out_dir / "tilt", d)
    summary.append(f"tilt +y: {d['headline_deg']:.2f} deg ({d.get('criterion')})" if d.get("headline_deg")
                   is not None else "tilt +y: no collapse up to the largest tilt")
    summary.append(f"rigid limit +y (associative / Coulomb): {tiltmod._limit_cell(d.get('limit'))} deg")

    if importlib.util.find_spec("drystone.analyses.modal") is not None:
        log("[assess] 2/3 modal")
        try:
            from drystone.analyses import modal as modalmod

            m = modalmod.modal(case_path, out=out_dir / "modal", workers=workers, backend=backend, address=address,
                               overrides=overrides, log=log)
            f = list(m.get("frequencies_hz") or [])
            runs += 1 + bool(m.get("identification"))  # the settling run (+ the white noise, if identified)
            run_s += float((m.get("settle") or {}).get("wall_s") or 0.0)
            parts["modal"] = {"report": "modal/report.html", "frequencies_hz": f[:6]}
            summary.append("modal: " + (", ".join(f"{x:.3g}" for x in f[:4]) + " Hz" if f else "no frequencies"))
        except (TypeError, AttributeError, common.casemod.CaseError) as exc:  # its API or its refusal, said so
            parts["modal"] = {"skipped": f"{type(exc).__name__}: {exc}"}
            summary.append(f"modal: not run ({exc})")
    else:
        parts["modal"] = {"skipped": "the modal analysis is not in this checkout (drystone/analyses/modal.py)"}
        summary.append("modal: skipped (not in this checkout)")

    log(f"[assess] 3/3 PGA at collapse under {len(cfg['records'])} record(s), then fragility")
    fr = fragmod.fragility(case_path, cfg["records"], method="ida", duration_s=cfg["duration_s"], start=cfg["start"],
                           factor=cfg["factor"], cap=cfg["cap"], tolerance=cfg["tolerance"], fill=cfg["fill"],
                           max_runs=cfg["max_runs"], n_boot=cfg["n_boot"], overrides=overrides,
                           out=out_dir / "fragility", workers=workers, backend=backend, address=address, log=log)
    runs += fr["cost"]["runs"]
    run_s += fr["cost"]["run_wall_s"]
    parts["collapse"] = {"report": "fragility/collapse/report.html",
                         "records": {s: {"pga_at_collapse_g": r.get("pga_at_collapse_g"),
                                         "censored_at_g": r.get("censored_at_g"), "note": r.get("note")}
                                     for s, r in fr["records"].items()}}
    parts["fragility"] = {"report": "fragility/report.html",
                          "states": {k: {x: st.get(x) for x in ("theta", "beta", "theta_ci", "beta_ci", "reason")}
                                     for k, st in fr["states"].items()}}
    for k, st in fr["states"].items():
        summary.append(f"fragility {k}: {fragmod.describe(st, 'g')}")
    cost = {"runs": runs, "core_minutes": run_s / 60.0, "elapsed_s": time.time() - t0}
    summary.append(f"cost: {runs} runs, {cost['core_minutes']:.1f} core-minutes, {cost['elapsed_s'] / 60:.1f} min")
    data = {"analysis": "assess", "case": str(case_path), "overrides": list(overrides), "quick": quick,
            "settings": {k: (list(v) if isinstance(v, tuple) else v) for k, v in cfg.items()},
            "records_note": fragmod.ASSUMED_RECORDS, "parts": parts, "summary": summary, "cost": cost}
    common.write_json(out_dir / "assess.json", data, case=case_path, overrides=overrides)
    common.write_report(out_dir, f"Assessment: {case_path.name}", report_markdown(data))
    return dict(data, out_dir=str(out_dir))


def _tilt_wall(folder: Path, d: dict) -> float:
    import json

    try:
        info = json.loads((folder / "runs" / "towards_+y" / "summary.json").read_text())
        return float(info.get("wall_time_total_s") or 0.0)
    except (OSError, ValueError):
        return 0.0


def _limit_cell(lim) -> str:
    from drystone.analyses.tilt import _limit_cell as cell

    return cell(lim)


def report_markdown(data: dict) -> str:
    p = data["parts"]
    L = [f"# Assessment: {Path(data['case']).name}", "",
         f"Case `{data['case']}`" + (" — **quick** (short records, coarse search: a first look, not a result)"
                                     if data["quick"] else "") + ".", "", "## Summary", ""]
    L += [f"- {s}" for s in data["summary"]]
    t = p["tilt"]
    L += ["", "## Tilt", "", f"Towards +y at {t['rate_deg_s']:g} deg/s: "
          + (f"{t['headline_deg']:.2f} deg ({t['criterion']})" if t["headline_deg"] is not None else "no collapse")
          + f". [Tilt report]({t['report']})", "",
          "| towards | DEM onset (deg) | DEM reaction drop (deg) | rigid limit, associative / Coulomb (deg) |", "|---|---|---|---|",
          f"| +y | "
          f"{'-' if t['headline_deg'] is None else format(t['headline_deg'], '.2f')} | "
          f"{'-' if t.get('reaction_drop_deg') is None else format(t['reaction_drop_deg'], '.2f')} | "
          f"{_limit_cell(t.get('limit'))} |", "",
          "The rigid limit: the same wall of rigid stones as built (drystone/analyses/limit.py, "
          "docs/limit-analysis.md): usually above the DEM's reaction drop (compliant joints), not a bound.", "", "## Modal", ""]
    m = p["modal"]
    L.append(f"Skipped: {m['skipped']}." if "skipped" in m else
             f"Frequencies: {', '.join(f'{x:.3g}' for x in m['frequencies_hz'])} Hz. [Modal report]({m['report']})")
    L += ["", "## PGA at collapse", "", data["records_note"] + ".", "", "| record | PGA at collapse (g) |", "|---|---|"]
    for s, r in p["collapse"]["records"].items():
        b = r["pga_at_collapse_g"]
        L.append(f"| {s} | " + (f"({b[0]:g}, {b[1]:g}]" if b else f"> {r['censored_at_g']:g} (censored)"
                                 if r["censored_at_g"] is not None else "-") + " |")
    L += ["", f"[Collapse report]({p['collapse']['report']})", "", "## Fragility", "",
          "| state | θ (g) | β | reason if no fit |", "|---|---|---|---|"]
    for k, st in p["fragility"]["states"].items():
        L.append(f"| {k} | " + ("-" if st["theta"] is None else f"{st['theta']:.3g}") + " | "
                 + ("-" if st["beta"] is None else f"{st['beta']:.3g}") + f" | {st.get('reason') or ''} |")
    c = data["cost"]
    L += ["", f"[Fragility report]({p['fragility']['report']})", "", "## Cost", "",
          f"{c['runs']} runs, {c['core_minutes']:.1f} core-minutes (the runs' own wall time summed), "
          f"{c['elapsed_s'] / 60:.1f} min elapsed."]
    return "\n".join(L) + "\n"


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: python -m drystone assess CASE [--quick]")
