"""The rigid rocking block under a base pulse (drystone/mechanics/analytic.py rocking_pulse,
min_overturning_pulse): the reference of the collapse analysis's rocking check
(tests/test_analyses_collapse.py, Zhang & Makris 2001), itself checked here against
Housner's linearised closed form for a rectangular pulse on a slender block."""
import math

import pytest

import tolerances as tol
from drystone.mechanics import analytic as A

G = 9.81


@pytest.mark.parametrize("t1", [0.2, 0.5, 1.0])
def test_rectangular_pulse_against_housner(t1):
    b, h = 0.05, 1.0
    alpha = math.atan2(b, h)
    ref = A.rectangle_overturning(t1, b, h, G) / G
    got = A.min_overturning_pulse(math.pi / t1, b, h, None, G, hi_g=3 * ref, tol_g=1e-6 * ref, levels=40,
                                  shape="rectangle")
    assert got == pytest.approx(ref, rel=tol.ROCKING_LINEARISED_REL_PER_ALPHA2 * alpha ** 2)


def test_one_sine_pulse_thresholds():
    b, h = 0.2, 0.8
    p = math.sqrt(3 * G / (2 * math.hypot(b, h)))
    # below g tan(alpha) the block does not leave its base
    assert A.rocking_pulse(0.99 * G * b / h, 2 * p, b, h)["max_theta_rad"] == 0.0
    a = A.min_overturning_pulse(2 * p, b, h, None, G, levels=60, tol_g=1e-3)
    assert b / h < a < 1.0
    assert A.rocking_pulse(a * G, 2 * p, b, h)["overturned"]
    # a block that loses all its rocking at the impact (r = 0) needs a stronger pulse
    assert A.min_overturning_pulse(2 * p, b, h, 0.0, G, levels=60, tol_g=1e-3) > a
    with pytest.raises(ValueError):
        A.rocking_pulse(G, p, b, h, shape="square")
