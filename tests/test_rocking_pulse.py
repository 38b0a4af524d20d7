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


def _exact_peak(a, t1, b, h, g=G):
    """The largest rotation (rad) of the rigid block after a rectangular pulse of a (m/s^2)
    for t1 (s) that does not overturn it, exactly: during the pulse phi'' = p^2 ((a/g)
    cos(alpha - phi) - sin(alpha - phi)) has the energy integral phi'^2 = 4 p^2 sin(phi/2)
    ((a/g) cos(alpha - phi/2) - sin(alpha - phi/2)), so t1 = int_0^phi1 dphi / phi' (phi = u^2
    takes the start's 1/sqrt singularity away); after it phi'^2 / 2 + p^2 cos(alpha - phi) is
    conserved, so the peak has cos(alpha - phi_max) = cos(alpha - phi1) + phi1'^2 / (2 p^2)."""
    from scipy import integrate, optimize

    alpha = math.atan2(b, h)
    p2 = 3 * g / (2 * math.hypot(b, h))

    def k(phi):
        return a / g * math.cos(alpha - phi / 2) - math.sin(alpha - phi / 2)

    def speed2(phi):
        return 4 * p2 * math.sin(phi / 2) * k(phi)

    def dt_du(u):
        return 2 / math.sqrt(2 * p2 * k(0.0)) if u == 0 else 2 * u / math.sqrt(speed2(u * u))

    def time_to(phi1):
        return integrate.quad(dt_du, 0, math.sqrt(phi1), epsabs=0, epsrel=1e-13, limit=200)[0]

    phi1 = optimize.brentq(lambda x: time_to(x) - t1, 1e-12, alpha, xtol=1e-16, rtol=1e-15)
    return alpha - math.acos(math.cos(alpha - phi1) + speed2(phi1) / (2 * p2))


@pytest.mark.parametrize("b,t1,k", [(0.01, 0.2, 1.1), (0.05, 0.2, 1.05), (0.2, 0.3, 1.3), (0.02, 1.0, 1.01)])
def test_largest_rotation_after_a_rectangular_pulse_is_the_exact_peak(b, t1, k):
    """A pulse of k g tan(alpha), too weak to overturn the block: ``max_theta_rad`` is the
    peak of the exact rigid motion (``_exact_peak``), not the largest of the solver's steps."""
    h = 1.0
    a = k * G * b / h
    assert a < A.rectangle_overturning(t1, b, h, G)
    got = A.rocking_pulse(a, math.pi / t1, b, h, shape="rectangle")
    assert not got["overturned"]
    assert got["max_theta_rad"] == pytest.approx(_exact_peak(a, t1, b, h), rel=tol.ROCKING_PEAK_REL)


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
