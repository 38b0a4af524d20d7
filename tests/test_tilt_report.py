"""Tilt-table report (drystone/studies/tilt/study.py) on synthetic group folders (one tilt
analysis per run): statistics, the rate check and the tables, without YADE; the study's runs
are the tilt analysis's, with the study's protocols."""
import json

import pytest

from drystone.studies.tilt import study as tilt


def fake_run(root, name, seed, angle, rates=(2.0, 1.0), mu=0.4, kn=2e8, drop="absent"):
    """A finished run's summary.json; ``drop`` is its reaction-drop angle ("absent": a
    summary written before that angle was reported)."""
    d = root / name / tilt.RUN
    d.mkdir(parents=True)
    s = {"collapse_angle_deg": angle,
         "collapse": None if angle is None else {"detected_angle_deg": angle + 0.3, "criterion": "reaction_drop",
                                                 "first_blocks": [60, 61], "onset_block": 60},
         "inputs": {"materials": {"stone": {"density": 2300.0, "kn": kn, "kt": kn / 2, "mu": mu, "damping": 0.8}},
                    "geometry": {"generator": {"generator": "tilt_wall", "seed": seed}},
                    "stages": [{"kind": "gravity", "params": {}}]
                    + [{"kind": "tilt", "params": {"rate_deg_s": r}} for r in rates],
                    "provenance": {"overrides": [f"case.geometry.seed={seed}"]}},
         "run": {"wall_time_s": 100.0, "steps": 1000, "dt_s": 1e-4, "simulated_time_s": 0.1}}
    if drop != "absent":
        s["reaction_drop_angle_deg"] = drop
    (d / "summary.json").write_text(json.dumps(s))


def runs_json(root, names):
    (root / "runs.json").write_text(json.dumps({"runs": names}))


def test_statistics_rate_check_and_report(tmp_path):
    seeds, rate, sens = tmp_path / "seeds", tmp_path / "rate", tmp_path / "sens"
    angles = [14.0, 14.5, 15.0, None]  # the last wall did not collapse: counted, not averaged
    for k, a in enumerate(angles):
        fake_run(seeds, f"seed_{k}", k, a)
    runs_json(seeds, [f"seed_{k}" for k in range(5)])  # seed_4 never finished
    fake_run(rate, "paper_seed_0", 0, 14.15, rates=(1.0, 0.2))
    fake_run(sens, "mu_0.7", 0, 19.0, mu=0.7)
    runs_json(sens, ["mu_0.7", "kn_5e8"])
    s = tilt.build(seeds, rate, sens, tmp_path / "out", figures=False)
    st = s["seeds"]
    assert s["collapse_angles_deg"] == [14.0, 14.5, 15.0, None]
    assert (st["n_runs"], st["n_finished"], st["n_collapsed"]) == (5, 4, 3)
    assert st["mean_deg"] == pytest.approx(14.5) and st["sd_deg"] == pytest.approx(0.5)
    assert st["experiment_range_deg"] == pytest.approx([13.57, 15.09])
    assert st["mean_within_experiment_sd"] and st["n_within_experiment_sd"] == 3
    rc = s["rate_check"]
    assert rc["difference_deg"] == pytest.approx(-0.15) and rc["within_tolerance"]
    assert [r["name"] for r in s["sensitivity"]] == ["fem_calibration (seeds/seed_0)", "mu_0.7", "kn_5e8"]
    md = (tmp_path / "out" / "report.md").read_text()
    assert "| seed_4 | | not run |" in md and "| kn_5e8 | | | | | not run |" in md
    assert "Mean 14.50 deg" in md and "difference -0.15 deg" in md
    saved = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert saved["collapse_angles_deg"] == [14.0, 14.5, 15.0, None]


def test_rate_check_outside_tolerance_is_flagged(tmp_path):
    fake_run(tmp_path / "s", "seed_0", 0, 14.6)
    fake_run(tmp_path / "r", "paper_seed_0", 0, 14.3, rates=(1.0, 0.2))
    s = tilt.build(tmp_path / "s", tmp_path / "r", tmp_path / "none", tmp_path / "o", figures=False)
    assert s["rate_check"]["difference_deg"] == pytest.approx(0.3) and not s["rate_check"]["within_tolerance"]
    assert "OUTSIDE" in (tmp_path / "o" / "report.md").read_text()


def test_missing_seed_folder_is_an_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="make tilt"):
        tilt.build(tmp_path / "nothing", out=tmp_path / "o")


def test_extruded_walls_are_paired_by_seed(tmp_path):
    """The constant-section comparison pairs runs by seed (a seed missing on one side is
    left out) and reports the per-seed difference and its mean."""
    seeds, ext = tmp_path / "seeds", tmp_path / "ext"
    for k, (a, b) in enumerate([(14.0, 15.0), (13.5, 14.9), (14.2, None)]):
        fake_run(seeds, f"seed_{k}", k, a)
        (seeds / f"seed_{k}" / tilt.RUN / "geometry.json").write_text(
            json.dumps({"generator": {"depth_spread": 1 / 3, "thickness": 0.108}}))
        if b is not None:
            fake_run(ext, f"seed_{k}", k, b)
            (ext / f"seed_{k}" / tilt.RUN / "geometry.json").write_text(
                json.dumps({"generator": {"depth_spread": 0.0, "thickness": 0.108}}))
    s = tilt.build(seeds, tmp_path / "r", tmp_path / "n", tmp_path / "o", figures=False, extruded=ext)
    ex = s["extruded"]
    assert ex["seeds"] == [0, 1] and ex["differences_deg"] == pytest.approx([-1.0, -1.4])
    assert ex["mean_difference_deg"] == pytest.approx(-1.2) and ex["depth_spread"] == 0.0
    assert ex["statistics"]["mean_deg"] == pytest.approx(14.95)
    md = (tmp_path / "o" / "report.md").read_text()
    assert "| 1 | 14.90 | 13.50 | -1.40 |" in md and "lowers the angle by 1.20 deg" in md


def test_headline_both_angles_constant_section_first(tmp_path):
    """The headline gives the onset and the reaction-drop angles of both geometries, the
    constant-section walls first (the like-for-like comparison, in bold); a run without a
    reaction drop (None) is counted, not averaged; an old summary without the key and
    without histories reads as None."""
    seeds, ext = tmp_path / "seeds", tmp_path / "ext"
    for k, (a, ra, b, rb) in enumerate([(14.0, 14.6, 15.0, 15.3), (13.5, None, 14.9, 15.1), (14.2, "absent", 15.2, 15.5)]):
        fake_run(seeds, f"seed_{k}", k, a, drop=ra)
        fake_run(ext, f"seed_{k}", k, b, drop=rb)
    s = tilt.build(seeds, tmp_path / "r", tmp_path / "n", tmp_path / "o", figures=False, extruded=ext)
    rows = s["headline"]["rows"]
    assert [r["walls"] for r in rows] == ["constant_section", "varying_depth"]
    assert s["headline"]["like_for_like"] == "constant_section"
    assert rows[0]["reaction_drop"]["mean_deg"] == pytest.approx(15.3)
    assert rows[0]["onset"]["mean_deg"] == pytest.approx(15.033333333)
    assert rows[1]["reaction_drop_angles_deg"] == [14.6, None, None]
    assert rows[1]["reaction_drop"]["n_collapsed"] == 1 and rows[1]["reaction_drop"]["mean_deg"] == pytest.approx(14.6)
    assert s["extruded"]["reaction_drop"]["differences_deg"] == pytest.approx([-0.7])
    md = (tmp_path / "o" / "report.md").read_text()
    assert md.index("**constant section") < md.index("stones of varying depth (our hypothesis")
    assert "15.30, 15.10, 15.50: mean 15.30, sd 0.20" in md
    assert "| 14.3 |" in md  # the paper's model, on the reaction-drop column


def test_groups_are_tilt_analyses_with_the_studys_protocols(tmp_path, monkeypatch):
    """Each run of a group is one tilt analysis of cases/tilt_wall.toml towards +y with the
    group's protocol and overrides (the analysis's run_jobs captured: nothing runs), and the
    report reads it from the analysis's run folder. The rigid limit set beside each tilt
    analysis (an LP of the 40-stone wall, most of this test's time) is replaced by its
    could-not-read answer: test_analyses_tilt.py checks it on the tilt case."""
    from drystone.analyses import common
    from drystone.analyses import limit

    seen = []
    monkeypatch.setattr(limit, "beside_dem", lambda *a, **k: {"error": "not run (test)"})

    def capture(case, runs, root, label, common_=(), *a, **k):
        seen.append((str(case), list(runs), list(common_)))
        return {n: {"status": "failed", "error": "not run"} for n, _ in runs}

    monkeypatch.setattr(common, "run_jobs", capture)
    res = tilt.run_group("rate", tmp_path, workers=1, log=lambda m: None)
    assert res["paper_seed_0"]["status"] == "failed"
    (case, runs, over), = seen
    assert case == str(tilt.CASE.resolve()) and over == ["case.geometry.seed=0"]
    (name, (stages,)), = runs
    assert name == "towards_+y" and stages.startswith("stages=")
    import tomllib
    st = tomllib.loads("v = " + stages.split("=", 1)[1])["v"]
    assert [x["type"] for x in st] == ["gravity", "tilt", "tilt"]
    assert (st[1]["rate_deg_s"], st[1]["to_deg"]) == (1.0, 10.0)  # the paper's protocol
    assert (st[2]["rate_deg_s"], st[2]["max_deg"], st[2]["after_collapse"]) == (0.2, 25.0, 3.0)
    assert st[2]["until_collapse"] and st[1]["towards"] == st[2]["towards"] == "+y"
    assert json.loads((tmp_path / "rate" / "runs.json").read_text())["runs"] == ["paper_seed_0"]
    assert (tmp_path / "rate" / "paper_seed_0" / "tilt.json").is_file()
