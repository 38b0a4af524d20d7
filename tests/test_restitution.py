"""Rocking restitution (drystone/analyses/restitution.py): what the contact damping does to the
impacts of a slender block rocking on its corners, against Housner's rigid block.

Without YADE: Housner's r = 1 - 1.5 sin^2(alpha) against conservation of angular momentum
about the new corner, and the measurement on a synthetic rigid rocking history with a known
restitution. With YADE (the 0.2 x 0.2 x 0.8 m block released from 0.6 alpha, 1.25 s: one or
two impacts measured, each between two whole half-cycles, the same r as over 1.5 s; the runs
are shared by the tests of this module):

* heavily damped (0.8), r grows with K_n towards Housner's value, and the gap shrinks at
  least like the impact's duration (ROCKING_KN_DECADE_FACTOR);
* without damping the penalty contact is elastic: it does not reach Housner at any K_n, r
  stays near 1 (the rocking loses only what goes into the block's vibration on its
  contact); r decreases with the damping at K_n 2e8;
* the paper's K_n 2e8 N/m^3 and damping 0.8 give r clearly below Housner, in the range
  0.5-0.72 measured in the issue (within the measure's own bias, ROCKING_SUNK_BIAS_REL).
"""
import math

import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade
from drystone.analyses import restitution as rs


def test_housner_restitution_is_angular_momentum_about_the_new_corner():
    """Rigid block rocking on corner O = (b/2, 0) at angular velocity w (theta = 0) hits
    the platform with corner O' = (-b/2, 0); angular momentum about O' is kept:
    I_c w + m (r_O'c x v_c) = I_O w', v_c = w x r_Oc. w' / w = 1 - 1.5 sin^2(alpha)."""
    for b, h in ((0.2, 0.8), (0.3, 0.6), (0.1, 1.0)):
        m, w = 2.0, 1.3
        ic = m * (b * b + h * h) / 12
        c = np.array([0.0, h / 2])
        o, o2 = np.array([b / 2, 0.0]), np.array([-b / 2, 0.0])
        rc = c - o
        vc = w * np.array([-rc[1], rc[0]])  # w e_z x r (planar)
        r2 = c - o2
        h_before = ic * w + m * (r2[0] * vc[1] - r2[1] * vc[0])
        w_after = h_before / (ic + m * (r2 @ r2))
        assert w_after / w == pytest.approx(rs.housner_restitution(b, h), rel=tol.EXACT_REL)
    assert rs.housner_restitution() == pytest.approx(0.912, abs=5e-4)  # the 0.912 (three digits)
    assert rs.rocking_energy(0.0) == 0.0  # exact by construction: a factor sin(0) (any libm, any SIMD)
    R = 0.5 * math.hypot(rs.B, rs.H)
    assert rs.rocking_energy(rs.alpha(), mass=3.0) == pytest.approx(3.0 * rs.G * R * (1 - math.cos(rs.alpha())),
                                                                     rel=tol.EXACT_REL)
    # near upright the energy is m g R sin(alpha) theta (1 - theta cot(alpha) / 2 - theta^2 / 6 + O(theta^3)),
    # to every digit (as a difference of cosines it kept only ~7 digits at theta = 1e-9: cancellation)
    for th in (1e-9, -1e-7):
        t = abs(th)
        series = rs.G * R * math.sin(rs.alpha()) * t * (1 - t / (2 * math.tan(rs.alpha())) - t * t / 6)
        assert rs.rocking_energy(th) == pytest.approx(series, rel=tol.CHAINED_ULP_REL, abs=0)


@pytest.mark.parametrize("r", [0.95, 0.912, 0.75])
def test_measure_returns_the_restitution_of_a_rigid_rocking_history(r):
    """Housner's rocking equation integrated from 0.6 alpha with the angular velocity
    multiplied by r at each impact: every impact's measured restitution is r."""
    t, theta = rs.rigid_rocking(0.6 * rs.alpha(), r, 4)
    got = rs.restitution_per_impact(t, theta, min_fraction=0.0)
    assert len(got) == 4
    assert np.allclose(got, r, rtol=tol.ROCKING_AMPLITUDE_REL, atol=0)
    assert rs.amplitudes(t, theta)[0, 0] == pytest.approx(0.6 * rs.alpha(), rel=tol.ROCKING_AMPLITUDE_REL)


def test_damping_for_restitution_interpolates_the_curve():
    curve = [(0.0, 1.0), (0.05, 0.9), (0.1, 0.8), (0.3, 0.7), (0.8, 0.72)]  # flat or rising at the end: cut
    assert rs.damping_for_restitution(0.85, curve) == pytest.approx(0.075, rel=tol.EXACT_REL)
    assert rs.damping_for_restitution(0.7, curve) == pytest.approx(0.3, rel=tol.EXACT_REL)
    with pytest.raises(ValueError, match="outside"):
        rs.damping_for_restitution(0.6, curve)


def test_sunk_energy_tends_to_the_rigid_one():
    """The corner's sink scales as K_n^-1/2: at 1e14 N/m^3 the energies agree to 1e-3; at
    2e8 the sink takes 15 % of E at 0.6 alpha (ROCKING_SUNK_BIAS_REL's derivation)."""
    th = 0.6 * rs.alpha()
    m = rs.RHO * rs.B * rs.D * rs.H
    rigid = rs.rocking_energy(th, mass=m)
    assert rs.sunk_rocking_energy(th, 1e14) == pytest.approx(rigid, rel=1e-3)
    assert 1 - rs.sunk_rocking_energy(th, 2e8) / rigid == pytest.approx(0.15, abs=0.01)
    assert np.isnan(rs.sunk_rocking_energy(1e-5, 2e8))  # joint closed: not on a corner


# -- the block in YADE ------------------------------------------------------------------
@pytest.fixture(scope="module")
def rocking(tmp_path_factory):
    """measure(kn, damping) of the released block (1.25 s: the paper contact's second impact is
    followed by a whole half-cycle, crossing upright again, by then), each run once."""
    folder = tmp_path_factory.mktemp("rocking")
    done = {}

    def get(kn, damping):
        if (kn, damping) not in done:
            done[(kn, damping)] = rs.measure(folder / f"{kn:g}_{damping:g}", kn, damping, duration=1.25)
        return done[(kn, damping)]
    return get


@requires_yade
@pytest.mark.yade
def test_damped_restitution_approaches_housner_as_the_contact_stiffens(rocking):
    rh = rs.housner_restitution()
    r = {kn: rocking(kn, 0.8)["r"][0] for kn in (2e8, 2e9, 2e10)}
    assert r[2e8] < r[2e9] < r[2e10]
    assert abs(r[2e10] - rh) <= abs(r[2e9] - rh) / tol.ROCKING_KN_DECADE_FACTOR, r


@requires_yade
@pytest.mark.yade
def test_undamped_penalty_contact_does_not_reach_housner(rocking):
    """No damping: the contact is elastic (the sticking tangential spring too), so the
    impact dissipates nothing; the heel's downward speed comes back as the rise about the
    new corner. The rocking keeps all but what goes into the block's vibration: r is
    closer to 1 than to Housner's value even at K_n 2e10, and decreases with the damping
    at K_n 2e8 (0.02, 0.08, 0.8; undamped at 2e8 the first impact gives back some of the
    vibration the release on a bare corner started, r > 1, make free-decay's table)."""
    rh = rs.housner_restitution()
    r0 = rocking(2e10, 0.0)["r"][0]
    assert r0 > 0.5 * (1 + rh), r0
    r = [rocking(2e8, xi)["r"][0] for xi in (0.02, 0.08, 0.8)]
    assert r[0] > r[1] > r[2], r


@requires_yade
@pytest.mark.yade
def test_paper_contact_loses_far_more_than_housner(rocking):
    """K_n 2e8 N/m^3, damping 0.8 (the Sacsayhuaman paper's contact): each impact's r
    (those after which the block still rocks by 0.1 alpha or more: the first two) is in
    the issue's 0.5-0.72 widened by the measure's bias, and below Housner's 0.912 by more
    than that bias."""
    m = rocking(2e8, 0.8)
    big = [r for r, a in zip(m["r"], m["amplitude_after_rad"]) if a >= tol.ROCKING_SUNK_MIN_AMPLITUDE * rs.alpha()]
    assert len(big) >= 2, m
    for r in big:
        assert 0.5 * (1 - tol.ROCKING_SUNK_BIAS_REL) <= r <= 0.72 * (1 + tol.ROCKING_SUNK_BIAS_REL)
        assert r * (1 + tol.ROCKING_SUNK_BIAS_REL) < m["housner"]
