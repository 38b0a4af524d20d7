"""The closed forms themselves (drystone/mechanics/analytic.py)."""
import math

import pytest

import tolerances as tol
from drystone.mechanics import analytic


def test_toppling_tends_to_rigid_limit():
    """With a very stiff joint (kn = 1e15 N/m^3) the Winkler toppling angle is atan(b/h)
    within 0.05 deg (deficit ~ (rho g h / kn)^(1/3))."""
    assert analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 1e15) == pytest.approx(
        analytic.rigid_toppling_tilt_deg(0.2, 0.4), abs=tol.TOPPLING_RIGID_LIMIT_DEG)


def test_toppling_deficit_scales_with_compliance():
    """Deficit ratio for a 1000x stiffer joint is about 1000^(-1/3) = 0.1 (within 30 %:
    the power law holds asymptotically)."""
    rigid = analytic.rigid_toppling_tilt_deg(0.2, 0.4)
    d1 = rigid - analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e8)
    d2 = rigid - analytic.toppling_tilt_deg(0.2, 0.4, 0.2, 2300, 2e11)
    assert d1 > 0 and d2 > 0
    assert d2 / d1 == pytest.approx(0.1, rel=tol.TOPPLING_POWER_LAW_REL)


def test_sliding_angle():
    assert analytic.sliding_tilt_deg(0.4) == pytest.approx(math.degrees(math.atan(0.4)))
