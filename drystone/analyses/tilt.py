"""Collapse angle of any case on a tilting platform: ``python -m drystone tilt CASE
[--towards +y -y +x -x | all] [--rate 1.0] [--rate-check]``.

Each direction is one run of the case with its stages replaced (an override of
``stages``): the case's stages before its first tilt or excitation stage (its gravity,
settling, loads; a gravity stage, common.py ``GRAVITY``, is added if it has none), then the
platform tilted towards the direction at ``--rate`` deg/s until collapse (at most ``--max-deg``;
the run stops ``after_collapse`` s after the detection). Every run is an ordinary run
folder (``runs/towards_<dir>/``) that ``drystone run CASE --set stages=...`` would make.

**One headline angle per direction: the onset** (``headline_deg``, criterion ``onset``):
the tilt at which the motion that led to the collapse began, a stone moving faster than
5 mm per degree of tilt over 0.2 deg (drystone/mechanics/collapse.py ``onset``: measured per
degree of tilt, so it marks the same state at any rate). Details beside it:
``reaction_drop_deg`` (the Sacsayhuaman paper's reading, its Figure 13: the vertical
reaction of the moving stones 5 % below their weight; None when it did not drop before the
run stopped), ``detected_deg`` (when the run detected the collapse), ``first_stone``, and the
stones that collapsed by the package's one criterion at the end of the run
(drystone/analyses/common.py ``outcome``). A wall standing at ``--max-deg`` has no headline
(``reached`` false).

**Rate check** (``--rate-check``): each direction is run again, tilted at ``--rate`` to
``RATE_CHECK_LEAD_DEG`` below its headline, then at ``--check-rate`` (default a fifth of
the rate) until collapse; the two headlines agree when they differ by at most
``--rate-band`` deg (``RATE_BAND_DEG``), and the report says whether they do.

Writes into results/<case name>/tilt/ (or ``--out``): ``tilt.json`` ({"directions": {"+y":
{"headline_deg", "criterion", "onset_deg", "reaction_drop_deg", "detected_deg",
"first_stone", "collapsed_stones", "reached", "run", "rate_check", "limit"}}, protocol, provenance);
``limit``: the rigid-block limit angles of the same wall as built, {"associative_deg",
"coulomb_deg", "associative_status", "coulomb_status", "note"} (drystone/analyses/limit.py
``beside_dem``: usually above the DEM's reaction-drop angle, not a bound, docs/limit-analysis.md),
``tilt.png`` (largest stone displacement against tilt, per direction) and ``report.html``.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

from drystone.analyses import common
from drystone.mechanics.limit_analysis import FACETS

HELP = "collapse angle on a tilting platform, per direction, with a rate check -> tilt.json, report.html"

DIRECTIONS = ("+y", "-y", "+x", "-x")
#: the rate check agrees when the two headlines differ by at most this (deg): the tilt study's
#: band for its rate check (drystone/studies/tilt/study.py RATE_TOLERANCE_DEG is 0.2 deg for
#: the paper's wall; a generic wall, rattling, gets a wider one by default)
RATE_BAND_DEG = 0.5
#: the slower run is tilted at the main rate to this far below the first headline (deg)
RATE_CHECK_LEAD_DEG = 3.0
#: seconds run after a detected collapse (long enough for the reaction-drop reading)
AFTER_COLLAPSE_S = 2.0
CRITERION = ("onset: the tilt at which the motion that led to the collapse began, a stone moving faster than "
             "5 mm per degree of tilt over 0.2 deg (drystone/mechanics/collapse.py onset)")


def add_arguments(p) -> None:
    common.add_common_arguments(p)
    p.add_argument("--towards", nargs="+", default=["+y"], metavar="DIR",
                   help="directions the platform tilts towards: +y -y +x -x, or all (default +y: out of plane)")
    p.add_argument("--rate", type=float, default=1.0, help="tilt rate, deg/s (1.0)")
    p.add_argument("--max-deg", type=float, default=45.0, help="largest tilt, deg (45)")
    p.add_argument("--rate-check", action="store_true", help="run each direction again at a slower rate")
    p.add_argument("--check-rate", type=float, default=None, help="the slower rate, deg/s (default rate / 5)")
    p.add_argument("--rate-band", type=float, default=RATE_BAND_DEG,
                   help=f"the rate check agrees within this, deg ({RATE_BAND_DEG})")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a case key in every run (as drystone run --set)")


def main(args) -> int:
    backend, address = common.backend_of(args)
    res = tilt(args.case, args.towards, out=args.out, workers=args.workers, backend=backend, address=address,
               rate=args.rate, max_deg=args.max_deg, rate_check=args.rate_check, check_rate=args.check_rate,
               rate_band=args.rate_band, overrides=args.set)
    for d, r in res["directions"].items():
        print(f"towards {d}: {describe(r)}")
    print(f"report: {Path(res['out_dir']) / 'report.html'}")
    return 1 if any(r.get("status") == "failed" for r in res["directions"].values()) else 0


def describe(r: dict) -> str:
    if r.get("status") == "failed":
        return f"failed ({r.get('error', '')})"
    if not r["reached"]:
        return f"no collapse up to {r['max_tilt_deg']:.1f} deg"
    txt = f"collapse at {r['headline_deg']:.2f} deg (onset; first stone {r['first_stone']})"
    if r.get("reaction_drop_deg") is not None:
        txt += f", reaction drop {r['reaction_drop_deg']:.2f} deg"
    rc = r.get("rate_check")
    if rc:
        txt += (f"; at {rc['rate_deg_s']:g} deg/s: {rc['headline_deg']:.2f} deg, "
                f"{'agrees' if rc['agrees'] else 'DOES NOT agree'} within {rc['band_deg']:g} deg"
                if rc.get("headline_deg") is not None else f"; rate check: {rc.get('status')}")
    return txt


def _directions(towards) -> list[str]:
    ds = []
    for d in towards:
        for x in (DIRECTIONS if d == "all" else [d]):
            if x not in DIRECTIONS:
                raise common.casemod.CaseError(f"--towards: {x!r} is not one of {', '.join(DIRECTIONS)} or all")
            if x not in ds:
                ds.append(x)
    return ds


def stages_override(prefix: list[dict], towards: str, rate: float, max_deg: float, fast_to: float | None = None,
                    fast_rate: float | None = None, after_collapse: float = AFTER_COLLAPSE_S) -> str:
    """The ``stages=[...]`` override of one tilt run."""
    from drystone import tomlio

    tilt = []
    if fast_to is not None and fast_to > 0:
        tilt.append({"type": "tilt", "rate_deg_s": float(fast_rate), "to_deg": float(fast_to), "towards": towards})
    tilt.append({"type": "tilt", "rate_deg_s": float(rate), "until_collapse": True, "max_deg": float(max_deg),
                 "towards": towards, "after_collapse": float(after_collapse)})
    return "stages=" + tomlio.value(prefix + tilt)


def _run_name(d: str, suffix: str = "") -> str:
    return f"towards_{d}{suffix}"


def tilt(case, towards=("+y",), out=None, workers=None, backend: str = "local", address=None, rate: float = 1.0,
         max_deg: float = 45.0, rate_check: bool = False, check_rate: float | None = None,
         rate_band: float = RATE_BAND_DEG, overrides=(), lead=None, after_collapse: float = AFTER_COLLAPSE_S,
         log=print) -> dict:
    """The collapse angle of ``case`` tilted towards each direction (module docstring);
    returns what it writes to tilt.json, with ``out_dir``. ``lead``: (to_deg, rate_deg_s), a
    faster lead-in tilt before the tilt at ``rate`` (the tilt study's protocols: 2 deg/s to
    10 deg, then 1 deg/s); ``after_collapse``: seconds run after a detected collapse."""
    from drystone.model import case as casemod

    t0 = time.time()
    case_path = Path(case).resolve()
    casemod.load(case_path, list(overrides))  # a bad case or override: one line, before anything runs
    dirs = _directions(towards)
    if not rate > 0 or not 0 < max_deg <= 90:
        raise casemod.CaseError(f"{case}: --rate must be > 0 and --max-deg in (0, 90] deg")
    if lead is not None and not (0 < lead[0] < max_deg and lead[1] > 0):
        raise casemod.CaseError(f"{case}: the lead-in tilt must reach 0 < to_deg < --max-deg at a rate > 0, got {lead}")
    check_rate = rate / 5.0 if check_rate is None else check_rate
    if rate_check and not check_rate > 0:
        raise casemod.CaseError(f"{case}: --check-rate must be > 0")
    prefix = common.stages_before(case_path, overrides)
    out_dir = common.output_dir(case_path, "tilt", out)
    lead_to, lead_rate = lead if lead is not None else (None, None)
    runs = [(_run_name(d), [stages_override(prefix, d, rate, max_deg, lead_to, lead_rate, after_collapse)])
            for d in dirs]
    from drystone.analyses import limit as limitmod

    limits = limitmod.beside_dem(case_path, dirs, overrides, cache_dir=out_dir)  # seconds, before the runs
    log(f"[tilt] {len(runs)} direction(s) at {rate:g} deg/s: {', '.join(dirs)}")
    res = common.run_jobs(case_path, runs, out_dir, "tilt", list(overrides), workers, backend, address, log)
    directions = {d: _direction(res[_run_name(d)], _run_name(d)) for d in dirs}
    for d in dirs:
        directions[d]["limit"] = limits.get(d, limits)
    n_runs = len(runs)
    if rate_check:
        checks = []
        for d in dirs:
            h = directions[d].get("headline_deg")
            if h is None:
                directions[d]["rate_check"] = {"rate_deg_s": check_rate, "status": "not run (no collapse)"}
                continue
            fast_to = math.floor(max(0.0, h - RATE_CHECK_LEAD_DEG))
            checks.append((d, fast_to, (_run_name(d, "-slow"),
                                        [stages_override(prefix, d, check_rate, max_deg, fast_to or None, rate,
                                                         after_collapse)])))
        log(f"[tilt] rate check: {len(checks)} run(s) at {check_rate:g} deg/s")
        cres = common.run_jobs(case_path, [c for _, _, c in checks], out_dir, "tilt-rate-check", list(overrides),
                               workers, backend, address, log)
        n_runs += len(checks)
        for d, fast_to, (name, _) in checks:
            o = _direction(cres[name], name)
            hd = o.get("headline_deg")
            diff = None if hd is None else hd - directions[d]["headline_deg"]
            directions[d]["rate_check"] = {
                "rate_deg_s": check_rate, "fast_to_deg": fast_to, "headline_deg": hd,
                "reaction_drop_deg": o.get("reaction_drop_deg"), "difference_deg": diff, "band_deg": rate_band,
                "agrees": diff is not None and abs(diff) <= rate_band, "run": o.get("run"),
                "status": o.get("status")}
    data = {"analysis": "tilt", "case": str(case_path), "overrides": list(overrides),
            "protocol": {"stages_before_tilt": prefix, "rate_deg_s": rate, "max_deg": max_deg,
                         "lead": None if lead is None else {"to_deg": lead_to, "rate_deg_s": lead_rate},
                         "after_collapse_s": after_collapse,
                         "rate_check": ({"rate_deg_s": check_rate, "lead_deg": RATE_CHECK_LEAD_DEG,
                                         "band_deg": rate_band} if rate_check else None)},
            "headline": CRITERION, "collapse_criterion": common.CRITERION,
            "units": "deg (angles), m (displacements)",
            "directions": directions,
            "cost": {"runs": n_runs, "elapsed_s": time.time() - t0}}
    common.write_json(out_dir / "tilt.json", data, case=case_path, overrides=overrides)
    fig = tilt_figure(directions, out_dir, out_dir / "tilt.png")
    common.write_report(out_dir, f"Tilt: {case_path.name}", report_markdown(data), [fig])
    return dict(data, out_dir=str(out_dir))


def _direction(o: dict, name: str) -> dict:
    if o["status"] != "done":
        return {"status": "failed", "error": o.get("error"), "run": f"runs/{name}", "headline_deg": None,
                "reached": False}
    reached = o.get("onset_deg") is not None
    return {"status": "done", "headline_deg": o.get("onset_deg"), "criterion": "onset", "reached": reached,
            "onset_deg": o.get("onset_deg"), "reaction_drop_deg": o.get("reaction_drop_deg"),
            "detected_deg": o.get("detected_deg"), "first_stone": o.get("first_stone"),
            "collapsed_stones": o.get("collapsed_stones"), "left_model": o.get("left_model"),
            "in_plane_sliding": o.get("in_plane_sliding"), "max_tilt_deg": o.get("max_tilt_deg"),
            "run": f"runs/{name}", "wall_s": o.get("wall_s")}


def _curve(run_dir: Path):
    """(tilt deg, largest displacement of any stone since the end of gravity, mm) of a run."""
    import json

    import numpy as np

    from drystone.model.spec import stage_type
    from drystone.postprocess.summary import load_histories

    h = load_histories(run_dir)
    spec = json.loads((run_dir / "spec.json").read_text())
    grav = [st for st in spec["stages"] if stage_type(st) == "gravity"]
    t = np.asarray(h["t"])
    i0 = min(int(np.searchsorted(t, grav[-1]["end"] - 1e-9)), len(t) - 1) if grav else 0
    d = np.linalg.norm(np.asarray(h["pos"]) - np.asarray(h["pos"])[i0], axis=2).max(axis=1)
    return np.asarray(h["tilt_deg"])[i0:], 1e3 * d[i0:]


def tilt_figure(directions: dict, out_dir: Path, path: Path) -> Path:
    """Largest stone displacement (mm) against the platform's tilt (deg), one curve per
    direction (dashed: the rate check), the headline angles marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for d, r in directions.items():
        if r.get("status") != "done":
            continue
        x, y = _curve(out_dir / r["run"])
        line, = ax.plot(x, y, label=f"towards {d}")
        if r.get("headline_deg") is not None:
            ax.axvline(r["headline_deg"], color=line.get_color(), lw=0.8, ls=":")
        rc = r.get("rate_check") or {}
        if rc.get("run") and (out_dir / rc["run"] / "summary.json").is_file():
            x2, y2 = _curve(out_dir / rc["run"])
            ax.plot(x2, y2, "--", color=line.get_color(), lw=1, label=f"towards {d}, {rc['rate_deg_s']:g} deg/s")
    ax.set_xlabel("platform tilt (deg)")
    ax.set_ylabel("largest stone displacement (mm)")
    ax.set_yscale("symlog", linthresh=1.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    from drystone import atomic

    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def _f(x, fmt=".2f"):
    return "-" if x is None else format(x, fmt)


def _limit_cell(lim: dict | None) -> str:
    if not lim:
        return "-"
    if "error" in lim:
        return lim["error"]
    cone = lim.get("associative_cone_deg") or [None, None]
    # the exact cone's upper end where the pyramid's friction matters (more than 0.1 deg)
    wide = cone[1] is not None and lim.get("associative_deg") is not None and cone[1] - lim["associative_deg"] > 0.1
    return f"{_f(lim.get('associative_deg'))} / {_f(lim.get('coulomb_deg'))}" + (
        f" (exact cone up to {_f(cone[1])})" if wide else "") + (
        "" if lim.get("coulomb_status") == lim.get("associative_status") == "collapse"
        else f" ({lim.get('associative_status')} / {lim.get('coulomb_status')})")


def report_markdown(data: dict) -> str:
    p = data["protocol"]
    L = [f"# Tilt: {Path(data['case']).name}", "",
         f"Case `{data['case']}`: its stages before tilting ({', '.join(s['type'] for s in p['stages_before_tilt'])}), "
         f"then the platform tilted at {p['rate_deg_s']:g} deg/s until collapse (at most {p['max_deg']:g} deg).", "",
         f"**Headline angle** = {data['headline']}. The reaction-drop angle (the Sacsayhuaman paper's reading: the "
         "vertical reaction of the moving stones 5 % below their weight) and the detection angle are details.", "",
         "Rigid limit: the tilt angle atan(lambda) at which the same wall of rigid stones, as built, collapses "
         "(drystone/analyses/limit.py; associative / Coulomb friction): usually above the DEM's reaction drop, "
         "the DEM's joints being compliant, but not a bound (docs/limit-analysis.md). "
         f"The limit uses a {FACETS}-facet "
         "friction pyramid inside Coulomb's cone; where stones slip off the load direction the exact cone's angle "
         "can be higher, up to the value given.", "",
         "| towards | headline (onset) deg | reaction drop deg | detected deg | first stone | collapsed stones | "
         "rate check | rigid limit deg (assoc. / Coulomb) |", "|---|---|---|---|---|---|---|---|"]
    for d, r in data["directions"].items():
        if r.get("status") == "failed":
            L.append(f"| {d} | failed: {r.get('error')} | | | | | | {_limit_cell(r.get('limit'))} |")
            continue
        rc = r.get("rate_check")
        rtxt = "-" if not rc else (
            f"{_f(rc.get('headline_deg'))} deg at {rc['rate_deg_s']:g} deg/s: "
            f"{'agrees' if rc.get('agrees') else '**does not agree**'} within {rc.get('band_deg', 0):g} deg"
            if rc.get("headline_deg") is not None else str(rc.get("status")))
        head = _f(r["headline_deg"]) if r["reached"] else f"none up to {_f(r.get('max_tilt_deg'), '.1f')}"
        L.append(f"| {d} | {head} | {_f(r.get('reaction_drop_deg'))} | {_f(r.get('detected_deg'))} | "
                 f"{r.get('first_stone', '-')} | {' '.join(map(str, r.get('collapsed_stones') or [])) or '-'} | "
                 f"{rtxt} | {_limit_cell(r.get('limit'))} |")
    L += ["", "![largest stone displacement against tilt](tilt.png)", "",
          f"Collapsed stones at the end of each run: {data['collapse_criterion']}.", "",
          f"Cost: {data['cost']['runs']} run(s), {data['cost']['elapsed_s'] / 60:.1f} min."]
    return "\n".join(L) + "\n"
