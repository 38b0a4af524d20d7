"""Fragility against several intensity measures: the IMs of a run's record as applied
(studies.fragility.measures), T1 and its source, the fits per IM with the efficiency
criterion on synthetic runs of known dispersion, the case-resampling bootstrap, and the
report's section and figure (no YADE)."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure
from drystone.motions import excitation, intensity, spectra
from drystone.motions.record import G
from drystone.analyses import fragility_fit as F
from drystone.studies.fragility import measures as M
from drystone.studies.fragility import plan as P
from drystone.studies.fragility import study as S
from drystone.studies.sacsayhuaman import study as sacsay

STRIPES = np.round(np.arange(1, 11) * 0.1, 1)


def test_first_period_measured_or_assumed(monkeypatch):
    monkeypatch.setattr(sacsay, "wall_frequency", lambda: 2.5)
    t = M.first_period()
    assert t["measured"] and t["t1_s"] == pytest.approx(0.4, rel=tol.FEW_ULP_REL) and "measured" in t["source"]
    monkeypatch.setattr(sacsay, "wall_frequency", lambda: None)
    t = M.first_period()
    assert not t["measured"] and t["f1_hz"] == M.DEFAULT_F1_HZ and t["source"].startswith("ASSUMED")
    assert M.first_period(2.0)["t1_s"] == 0.5


def test_run_measures_are_those_of_the_record_as_applied(tmp_path):
    """The small plan's first run (record 1a cut to 2 s, scaled to 0.5 g): its PGA is the
    stripe, its PGV and Sa(T1) those of what excitation.for_stage gives the runner, and all
    three scale with the stripe (a 1.0 g run is twice a 0.5 g one)."""
    cfg = P.CONFIGS["small"]
    P.write(cfg, out_dir=tmp_path)
    run = P.load_plan(tmp_path)["runs"][0]
    t1 = 0.385
    m = M.run_measures(run["record_file"], run["pga_g"], t1, cfg.record_duration_s)
    acc, dt, _ = excitation.for_stage({"motion": "record", "record": run["record_file"], "pga_g": run["pga_g"],
                                       "duration": cfg.record_duration_s})
    assert len(acc) == round(cfg.record_duration_s / dt) + 1
    assert m["pga_g"] == pytest.approx(run["pga_g"], rel=tol.CHAINED_ULP_REL)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)])
    assert m["pgv_m_s"] == pytest.approx(np.abs(v).max(), rel=tol.EXACT_REL)
    assert m["sa_t1_g"] == pytest.approx(spectra.response_spectrum(acc, dt, [t1])[0] / G, rel=tol.EXACT_REL)
    m2 = M.run_measures(run["record_file"], 2 * run["pga_g"], t1, cfg.record_duration_s)
    for k in m:
        assert m2[k] == pytest.approx(2 * m[k], rel=tol.CHAINED_ULP_REL), k


def _synthetic_runs(seed=3, beta_pgv=0.3, sigma_v=0.5, sigma_sa=0.8, theta_v=0.4):
    """22 records x 10 PGA stripes. Each record has its own PGV/PGA ratio (lognormal, log-SD
    sigma_v, the same at every stripe); Sa(T1)/PGA is noisier (sigma_sa, per run). Each run's
    capacity in PGV is lognormal (median theta_v m/s, log-SD beta_pgv) and a run reaches DS1
    when its PGV exceeds it (DS2, DS3 at 2 and 4 x the capacity). In ln PGV the dispersion is
    beta_pgv; in ln PGA it is sqrt(beta_pgv^2 + sigma_v^2) = 0.58: PGV must come out best."""
    rng = np.random.default_rng(seed)
    ratio = rng.lognormal(math.log(1.0), sigma_v, 22)  # m/s per g
    rows = []
    for rec in range(22):
        for pga in STRIPES:
            pgv = pga * ratio[rec]
            cap = rng.lognormal(math.log(theta_v), beta_pgv)
            rows.append({"name": f"r{rec}-{pga}", "status": "done", "pga_g": float(pga), "pgv_m_s": float(pgv),
                         "sa_t1_g": float(pga * rng.lognormal(math.log(2.0), sigma_sa)),
                         "DS1": bool(pgv > cap), "DS2": bool(pgv > 2 * cap), "DS3": bool(pgv > 4 * cap)})
    return rows


def test_the_most_efficient_measure_is_the_one_the_damage_follows():
    """Synthetic runs whose damage follows PGV with beta 0.3: the fit in PGV recovers beta
    within SE_MULTIPLE standard errors (Fisher information of the fit itself), the fits in
    PGA and Sa(T1) have larger beta (PGA: about sqrt(0.3^2 + 0.5^2) = 0.58), and PGV is
    named the most efficient for every damage state that can be fitted."""
    rows = _synthetic_runs()
    im = S.fit_measures(rows, n_boot=100, seed=0)
    assert [m["key"] for m in im["measures"]] == ["pga_g", "pgv_m_s", "sa_t1_g"] and im["default"] == "pga_g"
    for ds in ("DS1", "DS2"):
        f = im["fits"]["pgv_m_s"][ds]["fit"]
        assert abs(f["beta"] - 0.3) < tol.SE_MULTIPLE * f["se_beta"], (ds, f)
        assert im["fits"]["pga_g"][ds]["fit"]["beta"] > f["beta"] and im["fits"]["sa_t1_g"][ds]["fit"]["beta"] > \
            f["beta"]
        assert im["most_efficient"][ds] == "pgv_m_s"
        b = im["fits"]["pgv_m_s"][ds]["bootstrap"]
        assert b["beta_ci"][0] < f["beta"] < b["beta_ci"][1] and b["method"] == "runs resampled"
    # theta in PGV: DS1 at the capacity's median 0.4 m/s, DS2 at twice it
    f1, f2 = im["fits"]["pgv_m_s"]["DS1"]["fit"], im["fits"]["pgv_m_s"]["DS2"]["fit"]
    assert abs(math.log(f1["theta"] / 0.4)) < tol.SE_MULTIPLE * f1["se_ln_theta"]
    assert abs(math.log(f2["theta"] / 0.8)) < tol.SE_MULTIPLE * f2["se_ln_theta"]


def test_fit_in_pga_per_run_equals_the_stripe_fit():
    """fit_runs on per-run PGAs groups them into the stripes: the same theta and beta as
    fit_states (the stripe fit of the report's main table), to the optimiser's convergence."""
    rows = _synthetic_runs()
    im = S.fit_measures(rows, n_boot=10)
    st = S.fit_states(rows, n_boot=10)
    for ds in ("DS1", "DS2"):
        a, b = im["fits"]["pga_g"][ds]["fit"], st[ds]["fit"]
        assert a["theta"] == pytest.approx(b["theta"], rel=tol.NUMERICAL_REL)
        assert a["beta"] == pytest.approx(b["beta"], rel=tol.NUMERICAL_REL)


def test_bootstrap_of_runs_spreads_where_the_stripe_bootstrap_cannot():
    """With one run per IM value, resampling within stripes reproduces the data in every
    replicate (no spread); resampling runs does not. Its 95 % interval of beta contains the
    estimate and has a half-width of the order of 1.96 SE (between 1 and 3 SE here)."""
    rows = _synthetic_runs()
    x = np.array([r["pgv_m_s"] for r in rows])
    z = np.array([r["DS1"] for r in rows])
    f = F.fit_runs(x, z)
    b = F.bootstrap_runs(x, z, n_boot=300, seed=1)
    half = 0.5 * (b["beta_ci"][1] - b["beta_ci"][0])
    assert b["failed"] == 0 and 1.0 * f.se_beta < half < 3.0 * f.se_beta
    xs, ns, zs = F.stripes_from_runs(x, z)
    same = F.bootstrap(xs, ns, zs, n_boot=20, seed=1)
    assert same["beta_ci"][0] == pytest.approx(same["beta_ci"][1], rel=tol.NUMERICAL_REL)
    with pytest.raises(ValueError, match="one length"):
        F.bootstrap_runs([1.0, 2.0], [True])


def test_report_names_the_measure_and_the_smallest_beta(tmp_path, monkeypatch):
    """report.md on synthetic runs (fit_step replaced): the IM section with T1 and its source
    (ASSUMED without an identification run), one row per DS and IM, the smallest beta named,
    and the figure of the curves per IM."""
    monkeypatch.setattr(sacsay, "wall_frequency", lambda: None)
    cfg = replace(P.CONFIGS["small"], n_boot=20)
    P.write(cfg, out_dir=tmp_path)
    rows = [dict(r, kn=1e8, mu=0.45, settled=True, steps=50000, yade_wall_s=150.0, wall_s=158.0, simulated_s=40.0,
                 dt_s=8e-4) for r in _synthetic_runs()]
    data = {"runs": {"done": len(rows), "failed": 0, "pending": 0, "unreadable": 0},
            "fits": S.fit_states(rows, n_boot=20), "cost": S.cost(rows, reference=[]), "rows": rows,
            "intensity_measures": dict(S.fit_measures(rows, n_boot=20), t1=M.first_period())}
    monkeypatch.setattr(S, "fit_step", lambda *a, **k: data)
    text = S.report(cfg, out_dir=tmp_path).read_text()
    assert "## Which intensity measure: PGA, PGV or Sa(T1)" in text
    assert "T1 = 0.385 s" in text and "**ASSUMED" in text
    assert "DS1: smallest β with **PGV**" in text
    f = data["intensity_measures"]["fits"]["pgv_m_s"]["DS1"]["fit"]
    assert f"| DS1 | PGV | {f['theta']:.3g} m/s | {f['beta']:.3g} **(smallest)** |" in text
    assert "## Fragility curves: P(DS | PGA)" in text  # the default curves still say their IM
    assert_figure(tmp_path / "fragility_im.png", (12, 4.2), 120)


def test_collect_adds_the_measures_to_each_planned_run(tmp_path):
    """collect on a plan with no finished run: every row pending, with its PGV and Sa(T1)."""
    cfg = P.CONFIGS["small"]
    P.write(cfg, out_dir=tmp_path)
    rows = S.collect(cfg, tmp_path, t1_s=0.385)
    assert len(rows) == 4 and all(r["status"] == "pending" for r in rows)
    for r, run in zip(rows, P.load_plan(tmp_path)["runs"]):
        m = M.run_measures(run["record_file"], run["pga_g"], 0.385, cfg.record_duration_s)
        assert r["pgv_m_s"] == m["pgv_m_s"] and r["sa_t1_g"] == m["sa_t1_g"]
    assert intensity.DAMPING == 0.05
