"""``assess --quick`` end to end on the smallest case that is shaken and tilted: one stone
(cases/examples/sliding_block_pulse.toml) under two short pulses; the joined report, its
links, and a cost that adds up the parts' runs."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import tolerances as tol
from conftest import requires_yade

CASES = Path(__file__).resolve().parents[1] / "cases" / "examples"


@pytest.mark.slow
@requires_yade
def test_assess_quick_one_stone(tmp_path):
    from drystone.analyses import assess
    from test_analyses_fragility import pulse_file

    recs = [pulse_file(tmp_path / "pulse_a.txt", 1.0), pulse_file(tmp_path / "pulse_b.txt", 3.5)]
    res = assess.assess(CASES / "sliding_block_pulse.toml", quick=True, records=recs, out=tmp_path / "out",
                        workers=1, log=lambda *a: None)
    out = Path(res["out_dir"])
    data = json.loads((out / "assess.json").read_text())
    p = data["parts"]
    for part in ("tilt", "collapse", "fragility"):
        assert (out / p[part]["report"]).is_file(), part
    # the stone (mu = 0.4) slides off its bed tilted towards +y at 5 deg/s: the onset lags
    # atan(mu), the rigid-plastic sliding angle, by the time the slide takes to reach 5 mm/deg
    slide = math.degrees(math.atan(0.4))
    assert slide - tol.QUICK_SLIDE_EARLY_DEG <= p["tilt"]["headline_deg"] <= slide + tol.QUICK_SLIDE_LAG_DEG
    # beside it, the rigid limit of the same stone as built: atan(mu), both frictions
    lim = p["tilt"]["limit"]
    assert lim["associative_deg"] == pytest.approx(slide, rel=tol.LIMIT_LP_REL)
    assert lim["coulomb_deg"] == pytest.approx(slide, rel=tol.LIMIT_ITERATION_REL)
    fr = json.loads((out / "fragility" / "fragility.json").read_text())
    modal = json.loads((out / "modal" / "modal.json").read_text())
    assert data["cost"]["runs"] == 1 + 1 + bool(modal.get("identification")) + fr["cost"]["runs"]
    assert len(modal["frequencies_hz"]) > 0 and min(modal["frequencies_hz"]) > 0
    assert data["cost"]["core_minutes"] > 0
    html = (out / "report.html").read_text()
    for link in ("tilt/report.html", "fragility/report.html", "fragility/collapse/report.html"):
        assert link in html
    assert "modal" in html.lower()
    assert "rigid limit" in html


@pytest.mark.slow
@requires_yade
def test_assess_quick_on_a_drawn_wall_with_a_re_entrant_stone(tmp_path):
    """A user's own wall as a CAD drawing: an L-shaped (re-entrant, two-part) stone with a
    stone seated in its notch and a slab over both, all free on a drawn platform
    (tests/test_dxf.py's L stone). ``assess --quick`` runs every part on it: the tilt
    onset, positive frequencies of the settled wall, a PGA-at-collapse bracket or a
    censored search per record, and the joined report."""
    from drystone.analyses import assess
    from test_analyses_fragility import pulse_file
    from test_dxf import L_STONE, write_dxf

    stones = {1: L_STONE, 2: [(400, 300), (1000, 300), (1000, 700), (400, 700)],
              3: [(0, 700), (1000, 700), (1000, 900), (0, 900)]}
    write_dxf(tmp_path / "wall.dxf", stones, layers={1: "free", 2: "free", 3: "free"},
              platform=[(-500, -100), (1500, -100), (1500, 0), (-500, 0)])
    case = tmp_path / "wall.toml"
    case.write_text('[case]\nname = "drawn_l_wall"\n'
                    'geometry = {generator = "dxf", file = "wall.dxf", thickness = 0.4}\n\n'
                    '[[stages]]\ntype = "gravity"\nduration = 0.4\nramp = 0.2\n\n[output]\ninterval = 0.02\n')
    recs = [pulse_file(tmp_path / "pulse_a.txt", 1.0), pulse_file(tmp_path / "pulse_b.txt", 3.5)]
    res = assess.assess(case, quick=True, records=recs, out=tmp_path / "out", workers=1, log=lambda *a: None)
    out = Path(res["out_dir"])
    data = json.loads((out / "assess.json").read_text())
    p = data["parts"]
    assert "skipped" not in p["modal"], p["modal"]
    assert len(p["modal"]["frequencies_hz"]) > 0 and min(p["modal"]["frequencies_hz"]) > 0
    assert 0.0 < p["tilt"]["headline_deg"] < 90.0
    col = json.loads((out / "fragility" / "collapse" / "collapse.json").read_text())
    assert set(col["records"]) == {"pulse_a", "pulse_b"}
    for r in col["records"].values():
        assert r["status"] in ("bracketed", "censored", "budget"), r
    html = (out / "report.html").read_text()
    for link in ("tilt/report.html", "modal/report.html", "fragility/report.html"):
        assert link in html
