"""Linearised modal analysis (drystone/mechanics/modal.py) against closed forms for one block on a
rigid base (a Winkler foundation: K_n per unit area normal, K_t tangential).

Block b (x) x d (y) x H (z), mass m, on a fixed platform, sunk by the static penetration
delta0 = m g / (K_n A) (A = b d): the exact equilibrium of the law. With h = H/2 the
height of the centroid above the block's bottom face:

* bouncing: w^2 = K_n A / m;
* torsion about z: the law's twist spring K_t J_p (drystone/mechanics/contact.py
  ``twist_spring``; the tangential spring K_t A_c acts at one point, the overlap's centroid
  below the block's centroid, which a twist does not move), J_p = A (b^2 + d^2) / 12 the
  footprint's polar moment, on J_z = m (b^2 + d^2) / 12: w^2 = K_t A / m;
* sliding-rocking in x-z (DOFs u_x, theta_y about the centroid): K = [[K_t A, -K_t A h_c],
  [-K_t A h_c, K_n I_y + K_t A h_c^2 - W h_c]], M = diag(m, J_y), with I_y = d b^3 / 12,
  W = m g and h_c = h - delta0/2 the height of the centroid above the overlap's centroid
  (mid-depth of the overlap), where both forces act: the lever arm of the tangential
  spring, and the shift -h_c theta of the overlap (it moves with the block's sides) under
  the load W: gravity's geometric stiffness -W h_c;
* the same in y-z with b and d swapped.

These are exact for the law (no small-delta0 approximation) up to the finite-difference
truncation, O((step / delta0)^2) = 1e-6 with the default step of 1e-3 delta0, and the
round-off of the overlap volumes (~1e-15 m on a 1e-3 m depth): the tolerance 1e-5 on
frequencies is 10 times the truncation. The block is slender and the joint soft so that
gravity's term is 17 % of the rocking stiffness: leaving it out fails the test by far.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import linalg

import tolerances as tol
from drystone.mechanics import modal

RHO, KN, KT = 2300.0, 2e7, 1e7
B, D, H = 0.2, 0.3, 1.0


def _box(x0, x1, y0, y1, z0, z1):
    return np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], float)


def _one_block(blocked="", flush=False):
    """The block on the large platform, or (``flush``) on a fixed pedestal of its own
    footprint, every side face flush with the pedestal's."""
    m = RHO * B * D * H
    delta0 = m * modal.G / (KN * B * D)
    platform = _box(-B / 2, B / 2, -D / 2, D / 2, -0.2, 0.0) if flush else _box(-1, 1, -1, 1, -0.2, 0.0)
    block = _box(-B / 2, B / 2, -D / 2, D / 2, -delta0, H - delta0)
    return modal.Assembly([platform, block], moving=[False, True], density=RHO, kn=KN, kt=KT,
                          blocked=["", blocked], ids=[0, 1]), m, delta0


def _rocking_sliding(b, d, m, delta0):
    """Closed-form frequencies (Hz) of the coupled sliding-rocking pair in the plane of b."""
    a = b * d
    h = H / 2
    hc = h - delta0 / 2
    W = m * modal.G
    K = np.array([[KT * a, -KT * a * hc], [-KT * a * hc, KN * d * b ** 3 / 12 + KT * a * hc ** 2 - W * hc]])
    M = np.diag([m, m * (b * b + H * H) / 12])
    return np.sqrt(linalg.eigh(K, M, eigvals_only=True)) / (2 * np.pi)


def test_mass_properties_of_a_box():
    m, c, inertia = modal.mass_properties(_box(0, B, 0, D, 0, H), RHO)
    assert m == pytest.approx(RHO * B * D * H, rel=tol.EXACT_REL)
    np.testing.assert_allclose(c, [B / 2, D / 2, H / 2], rtol=tol.EXACT_REL)
    np.testing.assert_allclose(inertia, np.diag([m * (D * D + H * H), m * (B * B + H * H), m * (B * B + D * D)]) / 12,
                               rtol=tol.EXACT_REL, atol=tol.EXACT_REL * m)


def test_one_block_on_a_winkler_foundation():
    asm, m, delta0 = _one_block()
    res = asm.modes()
    f = np.sort(res["frequency_hz"])
    bounce = np.sqrt(KN * B * D / m) / (2 * np.pi)
    torsion = np.sqrt(KT * B * D / m) / (2 * np.pi)
    expected = np.sort(np.concatenate([[bounce, torsion], _rocking_sliding(B, D, m, delta0),
                                       _rocking_sliding(D, B, m, delta0)]))
    np.testing.assert_allclose(f, expected, rtol=tol.MODAL_FREQUENCY_REL)
    assert res["residual"] < tol.MODAL_RESIDUAL  # the sunk block is in equilibrium
    assert res["asymmetry"] < tol.MODAL_ASYMMETRY
    # gravity's geometric stiffness matters here: without it the lowest rocking mode is
    # well off (more than 5 %)
    assert m * modal.G * (H / 2) / (KN * D * B ** 3 / 12) > 0.15
    # the lowest mode with stiffness is rocking-sliding in x (the narrow side): most of
    # the mass for a base motion along x, none along y
    rx, ry = asm.modes(direction=(1, 0, 0)), asm.modes(direction=(0, 1, 0))
    k0 = int(np.argmin(np.where(rx["frequency_hz"] > 0.1, rx["frequency_hz"], np.inf)))
    assert rx["effective_mass_ratio"][k0] > 0.5 and ry["effective_mass_ratio"][k0] < tol.EXACT_ABS
    assert rx["effective_mass_ratio"].sum() == pytest.approx(1.0, rel=tol.NUMERICAL_REL)


def test_sliding_stiffness_flush_with_a_pedestal():
    """The block on a fixed pedestal of its own footprint, every side face flush with the
    pedestal's (coplanar faces, drystone/mechanics/overlap.py). Sliding by u along x, its
    overlap gains the strip of its trailing side face inside the pedestal, d x delta0, and
    the normal tilts by delta0 / b, one way or the other with the sign of u: the normal
    force K_n V jumps sideways by K_n d delta0^2 either way (7.6 N here), a jump, no
    stiffness; and the tangential spring K_t A acts in the tilted tangent plane:
    K_xx = K_t A (1 - (delta0 / b)^2), K_yy = K_t A (1 - (delta0 / d)^2), the same either way.
    Central differences alone read the jump over twice the step as a stiffness (-11 K_t A)."""
    asm, m, delta0 = _one_block(flush=True)
    K = asm.stiffness()
    ix, iy = ([k for k, (b, c) in enumerate(asm.dofs) if c == axis][0] for axis in (0, 1))
    assert K[ix, ix] == pytest.approx(KT * B * D * (1.0 - (delta0 / B) ** 2), rel=tol.MODAL_FREQUENCY_REL)
    assert K[iy, iy] == pytest.approx(KT * B * D * (1.0 - (delta0 / D) ** 2), rel=tol.MODAL_FREQUENCY_REL)


def test_blocked_dofs_are_left_out():
    """A side block of the wall ("xYZ": moves in y, z and rotates about x only) keeps 3
    DOFs: bouncing and the y-z sliding-rocking pair."""
    asm, m, delta0 = _one_block("xYZ")
    assert [c for _, c in asm.modes()["dofs"]] == ["y", "z", "X"]
    f = np.sort(asm.modes()["frequency_hz"])
    bounce = np.sqrt(KN * B * D / m) / (2 * np.pi)
    np.testing.assert_allclose(f, np.sort(np.r_[bounce, _rocking_sliding(D, B, m, delta0)]), rtol=tol.MODAL_FREQUENCY_REL)


def test_no_contact_is_an_error():
    far = _box(0, 1, 0, 1, 5, 6)
    asm = modal.Assembly([_box(-1, 1, -1, 1, -0.2, 0.0), far], moving=[False, True], density=RHO, kn=KN, kt=KT)
    with pytest.raises(ValueError, match="no contact"):
        asm.modes()


def test_equilibrium_carries_the_shear_a_settled_state_stored():
    """Gravity tilted by 2 deg along x: at the as-built state the unloaded tangential
    spring leaves W sin(2 deg) out of balance (the situation of a recorded settled state,
    whose stored shear is not recorded). ``equilibrium`` finds the state where the spring
    carries it: the residual falls below 1e-6 W, and the block's material point at the
    contact (h_c below the centroid) has slid by W sin a / (K_t A) (0.1 %: the spring is
    linear, the normal stays vertical), while the block leans (the joint stays closed:
    the lean lifts the edge by less than the static penetration)."""
    asm, m, delta0 = _one_block()
    a = np.radians(2.0)
    asm.gravity = modal.G * np.array([np.sin(a), 0.0, -np.cos(a)])
    assert asm.residual(np.zeros(asm.ndof)) == pytest.approx(np.sin(a), rel=tol.EQUILIBRIUM_REL)
    q, hist = asm.equilibrium()
    assert hist[-1] < tol.EQUILIBRIUM_RESIDUAL
    ux = q[[k for k, (b, c) in enumerate(asm.dofs) if c == 0][0]]
    ty = q[[k for k, (b, c) in enumerate(asm.dofs) if c == 4][0]]
    hc = H / 2 - delta0 / 2
    assert ux - ty * hc == pytest.approx(m * modal.G * np.sin(a) / (KT * B * D), rel=tol.EQUILIBRIUM_REL)
    assert 0 < ty * B / 2 < delta0


@pytest.mark.yade
def test_modes_of_a_two_block_tower_match_its_free_vibration(tmp_path):
    """Cross-check of the linearised analysis against the dynamics (YADE, native contacts):
    two 0.2 x 0.2 x 0.4 m blocks stacked on the platform, lightly damped (xi = 0.02),
    pushed sideways at the top block's centroid (0.03 W, the joints stay closed) and
    released. The period of the top block's x velocity (zero crossings over the first
    cycles, dominated by the first mode) equals the first x-mode of drystone/mechanics/modal.py
    at the settled state within 3 % (the second mode rings at a few times the first and
    shifts single crossings; damping 0.02 lowers the frequency by 0.02 %)."""
    from conftest import have_yade, run_case
    if not have_yade():
        pytest.skip("YADE is not installed")
    from drystone.postprocess import identification as idf

    size = [0.2, 0.2, 0.4]
    w_top = RHO * 0.016 * modal.G
    boxes = [{"id": 1, "center_xy": [0.0, 0.0], "size": size}, {"id": 2, "center_xy": [0.0, 0.0], "size": size,
                                                                  "z0": 0.4}]
    case = {"case": {"geometry": {"generator": "boxes_on_platform", "mu": 0.7, "damping": 0.02, "density": RHO,
                                  "kn": 2e8, "kt": 1e8, "boxes": boxes}},
            "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.1}, {"type": "rest", "duration": 0.6}],
            "forces": [{"block": 2, "force": [0.03 * w_top, 0.0, 0.0], "start": 0.3, "end": 0.5}],
            "output": {"interval": 2e-4}}
    s, h, spec = run_case(case, tmp_path)
    win = h["t"] >= 0.5
    t = h["t"][win]
    v = h["vel"][win, list(h["block_ids"]).index(2), 0]
    up = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))[:4]
    period = np.diff(t[up]).mean()
    asm = idf.wall_assembly(tmp_path / "case", time_s=0.3)
    res = asm.modes(direction=(1, 0, 0))
    f = res["frequency_hz"]
    first_x = f[(f > 0) & (res["effective_mass_ratio"] > 0.01)].min()  # the first mode that moves along x
    assert 1.0 / period == pytest.approx(first_x, rel=tol.TOWER_FREQUENCY_REL)
