"""The pulse-overturning study (drystone/studies/pulse_overturning.py) without YADE: its cases
are Zhang & Makris's type-A pulse at omega_p / p for the block's p, valid case files; the
rigid block's amplitude at omega_p = 2 p is the one tests/test_analyses_collapse.py brackets;
its report and the docs' block carry the brackets beside the rigid values."""
import math

import pytest

import tolerances as tol
from drystone.model import case as casemod
from drystone.studies import pulse_overturning as P
from drystone.studies import readme_tables as rt
from drystone.units import GRAVITY as G


@pytest.mark.parametrize("ratio", P.RATIOS)
def test_cases_are_one_sine_period_at_the_ratio(ratio, tmp_path):
    c = P.case(ratio, 0.056)
    sine = c["stages"][1]
    p = math.sqrt(3 * G / (4 * 0.5 * math.hypot(P.B, P.H)))  # R the half-diagonal
    assert 2 * math.pi * sine["frequency_hz"] == pytest.approx(ratio * p, rel=tol.EXACT_REL)
    assert sine["duration"] * sine["frequency_hz"] == pytest.approx(1.0, rel=tol.EXACT_REL)
    geo = c["case"]["geometry"]
    assert geo["kn"] == P.KN and geo["damping"] == 0.056 and geo["mu"] == P.MU
    casemod.validate(c, "case.toml", tmp_path)  # a valid case


def test_report_and_docs_block(tmp_path):
    rows = [{"ratio": 2.0, "frequency_hz": 1.34, "rigid_g": 0.306,
             "dampings": {"0.8": {"bracket_g": [0.40, 0.42]}, "0.056": {"bracket_g": None}}}]
    data = {"dampings": [0.8, 0.056], "housner": {"housner": 0.912, "source": "measured"}, "p_rad_s": 4.22,
            "tolerance_g": 0.02, "rows": rows, "runs": 7, "wall_s": 120.0}
    text = P.report(data)
    assert "| 2 | 1.34 | 0.306 | 0.40-0.42 | 1.34 | standing at the cap | - |" in text
    (tmp_path / "pulse_overturning").mkdir()
    (tmp_path / "pulse_overturning" / "report.md").write_text(text)
    block = rt.pulse_overturning(tmp_path)
    assert "0.40-0.42" in block and "figures/pulse_overturning.png" in block
