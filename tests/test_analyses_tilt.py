"""``python -m drystone tilt`` (drystone/analyses/tilt.py) on one stone whose collapse angle
has a closed form: the 0.2 m cube of one_block.json (mu 0.4 < b/h = 1) slides at
atan(0.4) = 21.80 deg towards any direction. One analysis (two directions, each with its
rate check) is run once for the module; its runs tilt at 5 deg/s to 20 deg (the stone stands
still there: 20 deg is 1.8 deg below its sliding angle, as in the case file), then at the rate
measured: 2 deg/s, and 0.5 deg/s in the rate check (led in at 2 deg/s to 3 deg below the first
onset), the rate TILT_ANGLE_DEG is stated for (its onset is that after a lead-in to 15 deg and
1 deg/s within 0.003 deg; the 2 deg/s onset is 0.37 deg later, inside the check's 0.5 deg band)."""
import json
import math
from pathlib import Path

import pytest

import tolerances as tol
from conftest import requires_yade
from drystone import paths
from drystone.analyses import tilt as T

CASE = paths.ROOT / "cases" / "examples" / "one_block_tilt.toml"


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    out = tmp_path_factory.mktemp("tilt") / "tilt"
    return T.tilt(CASE, ["+y", "-x"], out=out, workers=1, rate=2.0, max_deg=30.0, rate_check=True, check_rate=0.5,
                  lead=(20.0, 5.0), log=lambda *a, **k: None)


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_one_headline_per_direction_at_the_sliding_angle(result):
    exact = math.degrees(math.atan(0.4))
    assert set(result["directions"]) == {"+y", "-x"}
    for d, r in result["directions"].items():
        assert r["criterion"] == "onset" and r["reached"]
        assert r["headline_deg"] == r["onset_deg"]
        rc = r["rate_check"]
        # the slower run (0.5 deg/s, the rate TILT_ANGLE_DEG is stated for) against atan(mu)
        assert rc["headline_deg"] == pytest.approx(exact, abs=tol.TILT_ANGLE_DEG)
        assert rc["agrees"] == (abs(rc["difference_deg"]) <= rc["band_deg"])
        assert rc["agrees"]
        assert r["first_stone"] == 1 and r["collapsed_stones"] == [1]


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_outputs(result):
    out = Path(result["out_dir"])
    data = json.loads((out / "tilt.json").read_text())
    assert data["directions"]["+y"]["headline_deg"] == result["directions"]["+y"]["headline_deg"]
    assert data["protocol"]["stages_before_tilt"][0]["type"] == "gravity"
    assert (out / "tilt.png").stat().st_size > 0
    html = (out / "report.html").read_text()
    assert "Headline angle" in html and "<img" in html
    # every run is an ordinary run folder
    for d in ("towards_+y", "towards_-x", "towards_+y-slow", "towards_-x-slow"):
        assert (out / "runs" / d / "summary.json").is_file()


def test_directions_and_protocol():
    assert T._directions(["all"]) == ["+y", "-y", "+x", "-x"]
    assert T._directions(["-x", "+y", "-x"]) == ["-x", "+y"]
    with pytest.raises(T.common.casemod.CaseError, match="'up'"):
        T._directions(["up"])
    pre = T.common.stages_before(paths.ROOT / "cases" / "tilt_wall.toml", [])
    assert [s["type"] for s in pre] == ["gravity"]  # the case's own tilt stages are replaced
    over = T.stages_override(pre, "-y", 0.2, 30.0, fast_to=10.0, fast_rate=1.0)
    from drystone.model import case as casemod
    c = casemod.load(paths.ROOT / "cases" / "tilt_wall.toml", [over])
    assert [s["type"] for s in c["stages"]] == ["gravity", "tilt", "tilt"]
    assert c["stages"][2]["until_collapse"] and c["stages"][2]["towards"] == "-y"
    assert c["stages"][1]["to_deg"] == 10.0


def test_bad_direction_is_one_line_exit_2(tmp_path, capsys):
    from drystone import cli

    assert cli.main(["tilt", str(CASE), "--towards", "up", "--out", str(tmp_path / "t")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_rigid_limit_beside_the_dem_angle(result):
    """tilt.json sets the rigid limit angle (both frictions) beside the DEM's: one block that
    slides, atan(mu) for both, and the DEM's onset (the slower rate check) at it within the tilt's
    tolerance; the report shows it."""
    exact = math.degrees(math.atan(0.4))
    out = Path(result["out_dir"])
    data = json.loads((out / "tilt.json").read_text())
    for d in ("+y", "-x"):
        lim = data["directions"][d]["limit"]
        assert lim["associative_status"] == lim["coulomb_status"] == "collapse"
        assert lim["associative_deg"] == pytest.approx(exact, rel=tol.LIMIT_LP_REL)
        assert lim["coulomb_deg"] == pytest.approx(exact, rel=tol.LIMIT_ITERATION_REL)
        rc = data["directions"][d]["rate_check"]
        assert rc["headline_deg"] == pytest.approx(lim["associative_deg"], abs=tol.TILT_ANGLE_DEG)
    assert "rigid limit deg" in (out / "report.html").read_text()


def test_rigid_limit_of_the_tilt_case():
    """The limit analysis the tilt analysis sets beside its runs (no YADE): one block, mu 0.4
    < b/h = 1, slides at atan(0.4) = 21.80 deg, both frictions, any direction."""
    from drystone.analyses import limit as L

    exact = math.degrees(math.atan(0.4))
    lims = L.beside_dem(CASE, ["+y", "-x"])
    for d in ("+y", "-x"):
        assert lims[d]["associative_deg"] == pytest.approx(exact, rel=tol.LIMIT_LP_REL)
        assert lims[d]["coulomb_deg"] == pytest.approx(exact, rel=tol.LIMIT_ITERATION_REL)
        assert T._limit_cell(lims[d]) == f"{exact:.2f} / {exact:.2f}"
    assert "error" in L.beside_dem(paths.ROOT / "cases" / "no_such_case.toml", ["+y"])
