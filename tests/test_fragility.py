"""Fragility study (issue 15, item 1): the binomial maximum-likelihood fit on synthetic data
with a known median and dispersion, its edge cases, the plan (records, stripes, seeded
draws), the collection/report step without YADE, and one tiny real run end to end."""
from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize, stats

import tolerances as tol
from conftest import assert_figure, requires_yade
from drystone import sweep
from drystone.motions import fema, readers
from drystone.analyses import fragility_fit as F
from drystone.studies.fragility import plan as P
from drystone.studies.fragility import study as S

STRIPES = np.round(np.arange(1, 11) * 0.1, 1)
THETA, BETA = 0.45, 0.40


def _synthetic(n_per_stripe: int, seed: int, theta=THETA, beta=BETA, x=STRIPES):
    rng = np.random.default_rng(seed)
    n = np.full(len(x), n_per_stripe)
    return x, n, rng.binomial(n, F.probability(x, theta, beta))


def _brute_force(x, n, z):
    """The maximum of the binomial likelihood found another way: Nelder-Mead on
    (ln theta, ln beta) from several starts, the best kept."""
    def nll(p):
        pr = np.clip(F.probability(x, math.exp(p[0]), math.exp(p[1])), 1e-300, 1 - 1e-16)
        return -np.sum(z * np.log(pr) + (n - z) * np.log1p(-pr))
    best = min((optimize.minimize(nll, [math.log(t0), math.log(b0)], method="Nelder-Mead",
                                  options={"xatol": 1e-10, "fatol": 1e-12, "maxiter": 20000})
                for t0 in (0.2, 0.5, 1.0) for b0 in (0.2, 0.6)), key=lambda r: r.fun)
    return math.exp(best.x[0]), math.exp(best.x[1])


# --- (a) known median and dispersion ----------------------------------------------------------------------
# Tolerances from the binomial sampling error. At stripe x_j, z_j ~ Binomial(n_j, p_j) with
# p_j = Phi(u_j), u_j = a + b ln x_j (a = -ln theta / beta, b = 1 / beta). The Fisher
# information of one Bernoulli outcome about u is phi(u)^2 / (p (1 - p)), so that of the
# stripes about (a, b) is I = sum_j n_j phi(u_j)^2 / (p_j (1 - p_j)) [1, ln x_j]^T [1, ln x_j],
# and the maximum-likelihood estimate is asymptotically normal with covariance I^-1. By the
# delta method (ln theta = -a/b, beta = 1/b) this gives SE(ln theta) and SE(beta)
# (fit.standard_errors). For theta = 0.45 g, beta = 0.40 on the ten stripes 0.1-1.0 g:
# n = 1000 per stripe -> SE(ln theta) = 0.0073, SE(beta) = 0.0071 (asserted below).
# Tolerance: 4 SE, which a correct estimator exceeds with probability 6e-5 per parameter
# (normal tail), and which is 3 % in theta and 7 % in beta: an estimator off by 10 % in
# beta, or a least-squares fit of the fractions, would be caught.
def test_fit_recovers_known_median_and_dispersion():
    x, n, z = _synthetic(1000, seed=15)
    se_t, se_b = F.standard_errors(x, n, THETA, BETA)
    assert tol.FISHER_SE_MIN < se_t < tol.FISHER_SE_MAX and tol.FISHER_SE_MIN < se_b < tol.FISHER_SE_MAX, (se_t, se_b)
    f = F.fit(x, n, z)
    assert abs(math.log(f.theta / THETA)) < tol.SE_MULTIPLE * se_t, (f.theta, se_t)
    assert abs(f.beta - BETA) < tol.SE_MULTIPLE * se_b, (f.beta, se_b)
    # the optimiser's maximum is the likelihood's: Nelder-Mead from six starts agrees to
    # its own convergence (1e-10 in the log parameters; 1e-6 relative leaves margin)
    t2, b2 = _brute_force(x, n, z)
    assert f.theta == pytest.approx(t2, rel=1e-6) and f.beta == pytest.approx(b2, rel=1e-6)
    assert f.n_runs == 10000 and f.n_stripes == 10 and f.n_exceed == int(z.sum())


def test_fit_spread_matches_binomial_sampling_error():
    """Over 300 synthetic studies with 50 runs per stripe the estimates scatter as the
    Fisher information says. With R = 300 replicates the sample SD of an (approximately
    normal) estimator has relative standard error 1/sqrt(2 (R - 1)) = 4.1 %: tolerance 20 %
    (5 of those SEs, leaving 1-2 % for the asymptotic approximation at n = 50). The mean
    has standard error SE/sqrt(R): bias tolerance 4 of those plus the O(1/n) small-sample
    bias of a maximum-likelihood estimate (beta's is about -beta/(2 sum n_j w_j) ~ 1 %: 0.005)."""
    R, n_run = 300, 50
    se_t, se_b = F.standard_errors(STRIPES, np.full(10, n_run), THETA, BETA)
    lt, bs = [], []
    for r in range(R):
        f = F.fit(*_synthetic(n_run, seed=1000 + r))
        lt.append(math.log(f.theta))
        bs.append(f.beta)
    lt, bs = np.array(lt), np.array(bs)
    assert lt.std(ddof=1) == pytest.approx(se_t, rel=tol.REPLICATE_SD_REL)
    assert bs.std(ddof=1) == pytest.approx(se_b, rel=tol.REPLICATE_SD_REL)
    assert abs(lt.mean() - math.log(THETA)) < tol.SE_MULTIPLE * se_t / math.sqrt(R)
    assert abs(bs.mean() - BETA) < tol.SE_MULTIPLE * se_b / math.sqrt(R) + tol.ML_BETA_BIAS


def test_bootstrap_intervals_match_sampling_error():
    """Bootstrap (runs resampled within stripes): the 95 % interval of ln theta and beta has
    half-width 1.96 SE asymptotically; with 400 replicates its percentile ends carry ~10 %
    error, so within 30 %. It contains the fit, and the band contains the fitted curve."""
    x, n, z = _synthetic(200, seed=3)
    f = F.fit(x, n, z)
    b = F.bootstrap(x, n, z, n_boot=400, seed=1)
    se_t, se_b = F.standard_errors(x, n, f.theta, f.beta)
    half_t = 0.5 * math.log(b["theta_ci"][1] / b["theta_ci"][0])
    half_b = 0.5 * (b["beta_ci"][1] - b["beta_ci"][0])
    assert half_t == pytest.approx(1.96 * se_t, rel=tol.BOOTSTRAP_HALF_WIDTH_REL)
    assert half_b == pytest.approx(1.96 * se_b, rel=tol.BOOTSTRAP_HALF_WIDTH_REL)
    assert b["theta_ci"][0] < f.theta < b["theta_ci"][1] and b["beta_ci"][0] < f.beta < b["beta_ci"][1]
    g = np.asarray(b["grid"])
    assert np.all(np.asarray(b["band_lo"]) <= f.probability(g) + tol.BOOTSTRAP_BAND_SLACK)
    assert np.all(np.asarray(b["band_hi"]) >= f.probability(g) - tol.BOOTSTRAP_BAND_SLACK)
    assert b["failed"] == 0
    # seeded: the same seed gives the same intervals
    assert F.bootstrap(x, n, z, n_boot=400, seed=1)["theta_ci"] == b["theta_ci"]


# --- (b) edge cases ---------------------------------------------------------------------------------------
def test_stripes_at_zero_and_one_enter_the_likelihood():
    x = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    n = np.full(6, 20)
    z = np.array([0, 0, 4, 9, 20, 20])  # two 0 % and two 100 % stripes
    f = F.fit(x, n, z)
    assert 0.3 < f.theta < 0.45 and 0 < f.beta < 1
    t2, b2 = _brute_force(x, n, z)
    assert f.theta == pytest.approx(t2, rel=1e-6) and f.beta == pytest.approx(b2, rel=1e-6)
    b = F.bootstrap(x, n, z, n_boot=200, seed=0)
    assert b["theta_ci"][0] <= f.theta <= b["theta_ci"][1]
    assert 0 <= b["failed"] < 200  # resamples that happen to be separated are counted, not fitted


@pytest.mark.parametrize("x, z, words", [
    ([0.5], [3], "fewer than 2"),
    ([0.5, 0.5], [3, 4], "fewer than 2"),
    ([0.1, 0.2, 0.3], [0, 0, 0], "no run reached"),
    ([0.1, 0.2, 0.3], [10, 10, 10], "every run reached"),
    ([0.1, 0.2, 0.3], [0, 10, 10], "complete separation"),
    ([0.1, 0.2, 0.3], [0, 4, 10], "quasi-complete separation"),
    ([0.1, 0.2, 0.3], [0, 0, 4], "quasi-complete separation"),
])
def test_impossible_fits_are_refused_with_the_reason(x, z, words):
    with pytest.raises(F.FitError, match=words):
        F.fit(x, [10] * len(x), z)
    assert words in F.why_no_fit(x, [10] * len(x), z)


def test_a_flat_fit_is_refused_not_overflowed():
    """The same fraction at every stripe (a bootstrap resample can draw it): the slope is
    round-off and the median exp(-a / b) beyond any float, or below any; a FitError saying so, which the
    bootstrap counts as a failed fit, not an OverflowError that ends the study."""
    for z in ([1, 1, 1], [5, 5, 5]):  # the median far above the stripes, and far below them
        with pytest.raises(F.FitError, match="beyond any number"):
            F.fit([0.6, 0.9, 1.2], [6, 6, 6], z)


def test_malformed_input_is_a_value_error():
    with pytest.raises(ValueError, match="0 <= z <= n"):
        F.fit([0.1, 0.2], [10, 10], [3, 11])
    with pytest.raises(ValueError, match="positive"):
        F.fit([0.0, 0.2], [10, 10], [3, 5])
    x, n, z = F.stripes_from_runs([0.2, 0.1, 0.2, 0.1, 0.3], [1, 0, 0, 1, 1])
    assert x.tolist() == [0.1, 0.2, 0.3] and n.tolist() == [2, 2, 1] and z.tolist() == [1, 1, 1]


# --- (c) the plan -----------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def full_plan(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    path = P.write("full", out_dir=d / "out")
    return path, json.loads(path.read_text()), d


def test_plan_covers_the_far_field_set_and_stripes(full_plan):
    path, plan, d = full_plan
    cat = fema.catalogue("farfield")
    ids = sorted({c["record_id"] for c in cat})
    assert len(ids) == 22  # FEMA P695 far-field set: 22 pairs
    assert [r["record_id"] for r in plan["records"]] == ids
    assert {r["component"] for r in plan["records"]} == {"a"}
    assert P.CONFIGS["full"].stripes_g == (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
    assert len(plan["runs"]) == 22 * 10
    assert {(r["record_id"], r["pga_g"]) for r in plan["runs"]} == {(i, s) for i in ids for s in STRIPES}
    # what the analysis is given: the records as FEMA ids, the stripes, no record cut, one draw per run in
    # the analysis's order (record by record, stripes increasing), named as the analysis names its runs
    a = plan["analysis"]
    assert a["method"] == "stripes" and a["levels_g"] == STRIPES.tolist() and plan["common_overrides"] == []
    assert a["records"] == [f"fema:farfield:{i}a" for i in ids]
    assert [(r["record_id"], r["pga_g"]) for r in plan["runs"]] == [(i, s) for i in ids for s in STRIPES]
    assert len(P.draws(plan)) == 220 and len({r["name"] for r in plan["runs"]}) == 220
    for r in plan["runs"]:
        assert r["name"] == f"{Path(r['record_file']).stem}-pga_{r['pga_g']:g}"
        assert Path(r["record_file"]).is_file() and Path(r["record_file"]).parent == P.analysis_dir(d / "out") / "records"


def test_records_are_the_packages_samples(full_plan):
    """A written record read back by the package's reader is the FEMA record exactly."""
    _, plan, _ = full_plan
    for rec in plan["records"][:3]:
        r = readers.read(rec["file"])
        ref = fema.load(rec["record_id"], rec["component"])
        assert r.dt == ref.dt and np.array_equal(r.acc, ref.acc)


def test_draws_are_seeded_and_within_their_distributions(full_plan):
    _, plan, d = full_plan
    m, k = plan["distributions"]["mu"], plan["distributions"]["kn"]
    # mu: Ogawa et al. Table 2 (9 in-situ values) -> lognormal
    tab2 = np.array([0.57, 0.53, 0.41, 0.42, 0.39, 0.43, 0.39, 0.45, 0.50])
    assert m["values"] == tab2.tolist()
    assert m["median"] == pytest.approx(math.exp(np.log(tab2).mean()), rel=tol.EXACT_REL)
    assert m["beta"] == pytest.approx(np.log(tab2).std(ddof=1), rel=tol.EXACT_REL)
    assert (k["low"], k["high"], k["kt_over_kn"]) == (5e7, 2e8, 0.5)
    mu = np.array([r["mu"] for r in plan["runs"]])
    kn = np.array([r["kn"] for r in plan["runs"]])
    kt = np.array([r["kt"] for r in plan["runs"]])
    assert np.all(mu > 0)
    # kn rounded to 4 significant digits: within [low, high] to that rounding
    assert np.all(kn >= k["low"] * (1 - tol.FOUR_DIGITS_REL)) and np.all(kn <= k["high"] * (1 + tol.FOUR_DIGITS_REL))
    assert np.allclose(kt, 0.5 * kn, rtol=tol.KT_ROUNDING_REL)
    # the 220 draws follow the stated distributions (Kolmogorov-Smirnov; seeded, so this
    # is a fixed check: a wrong distribution, e.g. beta off by a factor 2, gives p < 1e-6)
    assert stats.kstest(np.log(mu), "norm", args=(math.log(m["median"]), m["beta"])).pvalue > tol.KS_P_MIN
    u = (np.log(kn) - math.log(k["low"])) / (math.log(k["high"]) - math.log(k["low"]))
    assert stats.kstest(np.clip(u, 0, 1), "uniform").pvalue > tol.KS_P_MIN
    # reproducible: rebuilding gives the same draws; each run's draw depends on its key only
    again = P.build(P.CONFIGS["full"], d / "out")
    assert [(r["mu"], r["kn"]) for r in again["runs"]] == [(r["mu"], r["kn"]) for r in plan["runs"]]
    small = P.build(P.CONFIGS["small"], d / "out")
    full_by = {(r["record_id"], r["pga_g"]): r for r in plan["runs"]}
    assert len(small["runs"]) == 4
    for r in small["runs"]:
        assert (r["mu"], r["kn"]) == (full_by[(r["record_id"], r["pga_g"])]["mu"],
                                      full_by[(r["record_id"], r["pga_g"])]["kn"])
    # a different seed gives different draws
    other = P.build(replace(P.CONFIGS["small"], seed=1), d / "out")
    assert [r["mu"] for r in other["runs"]] != [r["mu"] for r in small["runs"]]


def test_small_plan_validates(tmp_path, monkeypatch):
    """The small plan as the fragility analysis runs it (its run_jobs captured, nothing run):
    4 valid runs (keys, records, time step), records cut, each with its own draw."""
    from drystone.analyses import common

    seen = []

    def capture(case, runs, root, label, common_=(), *a, **k):
        seen.append((case, [sweep.Job(n, str(case), list(common_) + list(o), str(Path(root) / "runs" / n))
                            for n, o in runs]))
        raise KeyboardInterrupt

    monkeypatch.setattr(common, "run_jobs", capture)
    r = S.run("small", out_dir=tmp_path / "out")
    assert r["interrupted"] and len(seen) == 1
    jobs = seen[0][1]
    plan = P.load_plan(tmp_path / "out")
    assert [j.name for j in jobs] == [r["name"] for r in plan["runs"]] and len(jobs) == 4
    assert all("stages.1.duration=2.0" in j.overrides and "stages.2.duration=3.0" in j.overrides for j in jobs)
    for j, r in zip(jobs, plan["runs"]):
        assert f"contact.mu={r['mu']!r}" in j.overrides and f"stages.1.pga_g={r['pga_g']!r}" in j.overrides
    prints = sweep.validate(jobs)
    assert len(set(prints.values())) == 4


# --- collection, fit and report without YADE ------------------------------------------------------------------
def test_damage_states_are_nested():
    assert S.damage_states({"collapsed": [], "max_out_of_plane_m": 0.005}) == {"DS1": False, "DS2": False,
                                                                                "DS3": False}
    assert S.damage_states({"collapsed": [], "max_out_of_plane_m": 0.02}) == {"DS1": True, "DS2": False,
                                                                               "DS3": False}
    assert S.damage_states({"collapsed": [], "max_out_of_plane_m": 0.06}) == {"DS1": True, "DS2": True,
                                                                               "DS3": False}
    assert S.damage_states({"collapsed": [38], "max_out_of_plane_m": 0.003}) == {"DS1": True, "DS2": True,
                                                                                  "DS3": True}


def test_fit_states_figure_and_cost_on_synthetic_runs(outdir):
    rng = np.random.default_rng(7)
    rows = []
    for rid in range(1, 23):
        for pga in STRIPES:
            d = rng.lognormal(math.log(0.02 * (pga / 0.3) ** 2), 0.8)  # residual (m)
            coll = d > 0.3
            rows.append({"name": f"r{rid}-{pga}", "status": "done", "pga_g": float(pga), "record_id": rid,
                         "kn": 1e8, "mu": 0.45, **S.damage_states({"collapsed": [1] if coll else [],
                                                                    "max_out_of_plane_m": d}),
                         "steps": 50000, "yade_wall_s": 150.0, "wall_s": 158.0, "simulated_s": 40.0,
                         "dt_s": 5.666e-4 * math.sqrt(2e8 / 1e8)})
    states = S.fit_states(rows, n_boot=100, seed=0)
    thetas = [states[n]["fit"]["theta"] for n in ("DS1", "DS2", "DS3")]
    assert thetas == sorted(thetas)  # nested states: the medians increase
    for e in states.values():
        assert sum(s["runs"] for s in e["stripes"]) == 220 and e["bootstrap"]["theta_ci"] is not None
    assert_figure(S.figure(states, outdir / "fragility.png"), (12, 4.2), 120)
    c = S.cost(rows, reference=[{"rest_s": 2.0}])
    assert c["per_step_ms"] == pytest.approx(3.0) and c["overhead_s"] == pytest.approx(8.0)
    pr = c["projection"]["expected"]
    assert pr["runs"] == 220
    mk = [pr["makespan_hours"][str(w)] for w in S.WORKERS]
    assert mk == sorted(mk, reverse=True) and mk[0] == pytest.approx(pr["core_hours"])
    assert mk[1] >= pr["core_hours"] / 2 and mk[-1] == pytest.approx(pr["longest_run_min"] / 60)
    assert c["projection"]["upper bound"]["core_hours"] > pr["core_hours"]
    assert set(c["projection"]) == {"expected", "upper bound"}  # no Table 3 step cost given
    c2 = S.cost(rows, reference=[{"rest_s": 2.0, "steps": 1000, "yade_wall_s": 6.0}])
    assert c2["projection"]["expected, Table 3 step cost"]["core_hours"] > c2["projection"]["expected"]["core_hours"]


def test_lpt_makespan():
    assert S._lpt_makespan([3, 3, 2, 2, 2], 2) == 7
    assert S._lpt_makespan([5, 1, 1], 10) == 5


# --- (d) one tiny real run end to end ----------------------------------------------------------------------
@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_tiny_study_end_to_end(outdir):
    """One record (1a, cut to 1 s) at two stripes (the analysis needs two), rest capped at
    1.5 s (4.5 s simulated each, about 30-60 s here): plan -> the fragility analysis
    (stripes, the study's draws) -> residuals -> damage states -> report. One run per stripe
    cannot be fitted whatever it gives (none, both, or a jump between the stripes: complete
    separation; the report must say why); running the study again reuses the finished runs."""
    cfg = replace(P.CONFIGS["small"], name="tiny", record_ids=(1,), stripes_g=(0.4, 0.8), record_duration_s=1.0,
                  rest_max_s=1.5, n_boot=50)
    r = S.run(cfg, workers=1, out_dir=outdir / "out")
    assert not r["failed"] and not r["interrupted"], r
    assert r["analysis"]["method"] == "stripes" and r["analysis"]["draws_given"] == P.draws(P.load_plan(outdir / "out"))
    rep = S.report(cfg, out_dir=outdir / "out")
    data = json.loads((outdir / "out" / "fragility.json").read_text())
    assert data["runs"]["done"] == 2 and data["planned_runs"] == 2
    from drystone.studies.sacsayhuaman import analysis as an
    run_dir = P.analysis_dir(outdir / "out") / "runs" / "farfield_01a_MUL009-pga_0.8"
    res = an.residuals(run_dir)
    rows = list(__import__("csv").DictReader(open(outdir / "out" / "runs.csv")))
    assert len(rows) == 2 and rows[1]["status"] == "done" and rows[1]["name"] == run_dir.name
    rows = rows[1:]
    assert float(rows[0]["max_out_of_plane_mm"]) == pytest.approx(1e3 * res["max_out_of_plane_m"],
                                                                  rel=tol.CSV_READBACK_REL)
    assert rows[0]["DS1"] == str(S.damage_states(res)["DS1"])
    spec = json.loads((run_dir / "spec.json").read_text())
    assert {m["mu"] for m in spec["materials"].values()} == {P.load_plan(outdir / "out")["runs"][1]["mu"]}  # its draw
    ex = [s for s in spec["stages"] if s.get("type") == "excitation"][0]
    assert ex["end"] - ex["start"] == pytest.approx(1.0, abs=tol.RECORD_CUT_S)  # the record was cut to 1 s
    for e in data["fits"].values():
        assert e["fit"] is None and e["reason"]
    text = rep.read_text()
    assert "no fit" in text and "Projected full study (220 runs" in text
    assert data["cost"]["projection"]["expected"]["core_hours"] > 0
    assert (outdir / "out" / "fragility.png").is_file()  # markers and the reasons only: no curve to check
    again = S.run(cfg, workers=1, out_dir=outdir / "out")  # the finished run is reused, not run again
    sw = json.loads((run_dir.parent / "sweep.json").read_text())
    assert [x["status"] for x in sw["runs"]] == ["skipped (finished earlier)"] * 2 and not again["failed"]


def test_report_text_with_fitted_curves(tmp_path, monkeypatch):
    """report.md on synthetic fitted data (fit_step replaced): theta, beta and their
    intervals, the observed fractions, the projection and the assumptions are there."""
    cfg = replace(P.CONFIGS["small"], n_boot=50)
    P.write(cfg, out_dir=tmp_path)
    rng = np.random.default_rng(2)
    rows = [{"name": f"r{k}-{pga}", "status": "done", "pga_g": float(pga), "kn": 1e8, "mu": 0.45, "settled": True,
             **S.damage_states({"collapsed": [], "max_out_of_plane_m": rng.lognormal(math.log(0.03 * pga), 0.7)}),
             "steps": 50000, "yade_wall_s": 150.0, "wall_s": 158.0, "simulated_s": 40.0, "dt_s": 8e-4}
            for k in range(30) for pga in STRIPES]
    states = S.fit_states(rows, n_boot=50)
    data = {"runs": {"done": len(rows), "failed": 0, "pending": 0, "unreadable": 0}, "fits": states,
            "cost": S.cost(rows, reference=[]), "rows": rows}
    monkeypatch.setattr(S, "fit_step", lambda *a, **k: data)
    text = S.report(cfg, out_dir=tmp_path).read_text()
    f = states["DS1"]["fit"]
    assert f"| DS1 | {f['theta']:.3g} | " in text and f"| {f['beta']:.3g} | " in text
    assert "| 0.5 | 30 | " in text and "**Assumed**" in text and "Ogawa et al." in text
    assert "(assumed)" in text  # no Table 3 runs given: the rest is assumed
    assert "pipeline check" in text
