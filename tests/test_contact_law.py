"""The contact law's numpy kernels (drystone/mechanics/contact.py) against closed forms."""
import numpy as np
import pytest

import tolerances as tol
from drystone.mechanics import contact as law

N = np.array([[0.0, 0.0, 1.0]])


def test_contact_area_uniform_and_wedge_exact():
    """A uniform slab (e = d/2) gives V/d; a wedge (e = d/3) gives 2V/d: both exact."""
    A, d = 0.12, 2e-5
    assert law.contact_area([A * d], [d], [d / 2])[0] == pytest.approx(A, rel=tol.EXACT_REL)
    # wedge over a 0.3 x 0.4 footprint, depth 0 -> d: V = A d / 2
    assert law.contact_area([A * d / 2], [d], [d / 3])[0] == pytest.approx(A, rel=tol.EXACT_REL)


def test_contact_area_linear_depth():
    """Depth linear from d1 to d2 over a rectangle: V = A (d1+d2)/2, e = (d1^2+d1 d2+d2^2)/(3(d1+d2))."""
    A, d1, d2 = 0.5, 1e-5, 4e-5
    V = A * (d1 + d2) / 2
    e = (d1 * d1 + d1 * d2 + d2 * d2) / (3 * (d1 + d2))
    assert law.contact_area([V], [d2], [e])[0] == pytest.approx(A, rel=tol.NUMERICAL_REL)


def test_projection_direction_prefers_face_normal():
    """A normal 0.5 deg off the face normal is replaced by the face normal."""
    a = np.radians(0.5)
    n = np.array([[np.sin(a), 0.0, np.cos(a)]])
    faces_a = np.array([[[0, 0, 1.0], [1.0, 0, 0], [0, 0, -1.0]]])
    faces_b = np.array([[[0, 0, -1.0], [0, 1.0, 0]]])
    m, of_a = law.projection_direction(n, faces_a, faces_b)
    assert np.allclose(m, [[0, 0, 1]]) and of_a[0]


def test_stick_below_friction_limit():
    """A tangential increment below mu F_n is stored elastically: F = -K_t A u."""
    v = np.array([[1e-3, 0.0, 0.0]])
    fs, slip = law.shear_spring(N, v, np.zeros((1, 3)), np.array([0.1]), np.array([1e7]), np.array([0.5]),
                                np.array([100.0]), 1e-3)
    assert not slip[0]
    assert np.allclose(fs, [[-1e7 * 0.1 * 1e-3 * 1e-3, 0, 0]])


def test_slip_caps_at_coulomb():
    v = np.array([[1.0, 0.0, 0.0]])
    fs, slip = law.shear_spring(N, v, np.zeros((1, 3)), np.array([0.1]), np.array([1e7]), np.array([0.5]),
                                np.array([100.0]), 1e-3)
    assert slip[0]
    assert np.linalg.norm(fs) == pytest.approx(50.0)
    assert fs[0, 0] < 0  # opposes the relative motion


def test_damped_stick_never_exceeds_coulomb():
    """Spring 0.49 N near the cap 0.5 N plus a large tangential dashpot force: capped."""
    J = np.diag([1e-3, 1e-3, 0.0])[None]
    fd, _ = law.cap_damping(np.array([[-3.0, 0.0, 0.0]]), np.zeros((1, 3)), N, np.array([1.0]),
                            np.array([[-0.49, 0, 0]]), np.array([0.5]), np.zeros((1, 3)), np.array([0.1]), J)
    assert np.linalg.norm(fd + [[-0.49, 0, 0]]) <= 0.5 + tol.SLACK_TIGHT


def test_normal_damping_never_pulls():
    """Separating fast: the dashpot may cancel the elastic force but never pull."""
    J = np.diag([1e-3, 1e-3, 0.0])[None]
    fd, _ = law.cap_damping(np.array([[0.0, 0.0, -1e4]]), np.zeros((1, 3)), N, np.array([5.0]), np.zeros((1, 3)),
                            np.array([0.5]), np.zeros((1, 3)), np.array([0.1]), J)
    assert fd[0, 2] == pytest.approx(-5.0)


def test_shear_rotates_with_the_contact():
    fs = np.array([[3.0, 0.0, 0.0]])
    n = np.array([[np.sin(0.1), 0.0, np.cos(0.1)]])
    r = law.rotate_into_plane(fs, n)
    assert np.linalg.norm(r) == pytest.approx(3.0)
    assert abs(r[0] @ n[0]) < tol.EXACT_ABS


def test_critical_step_closed_form():
    """Undamped: 2/omega; with damping xi: (2/omega)(sqrt(1+xi^2)-xi)."""
    m, k = 2.0, 8e6
    w = np.sqrt(k / m)
    assert law.critical_time_step(m, k, 0.0) == pytest.approx(2 / w)
    assert law.critical_time_step(m, k, 0.8) == pytest.approx(2 / w * (np.sqrt(1.64) - 0.8))


def test_pair_properties_series_and_overrides():
    a = {"kn": 2e8, "kt": 1e8, "mu": 0.7, "damping": 0.8}
    b = {"kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.0}
    p = law.pair_properties(a, b, {"mu": 0.5})
    assert p["kn"] == 2e8 and p["kt"] == 1e8 and p["mu"] == 0.5 and p["damping"] == 0.4


def test_mobility_at_a_contact_point():
    """A free block (m, principal inertia I) against a fixed one: the effective mass along
    the normal, 1/(n.W n), is m at a point on the normal through the centre, and
    1/(1/m + r^2/I) at a lever arm r (the rocking edge); a fixed body adds nothing; a
    moment M at the point turns the block by I^-1 M and drags the point by -r x I^-1 M."""
    m, inertia, r = 10.0, np.array([0.5, 0.2, 0.3]), 0.1
    u = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    ra = np.zeros((2, 3))
    rb = np.array([[0.0, 0.0, -0.2], [r, 0.0, -0.2]])  # on the axis, then offset along x
    inv_i_b = np.repeat(np.diag(1.0 / inertia)[None], 2, axis=0)
    W = law.mobility(ra, rb, np.zeros(2), np.full(2, 1.0 / m), np.zeros((2, 3, 3)), inv_i_b)
    me = 1.0 / np.einsum("ki,kij,kj->k", u, W[:, :3, :3], u)
    # offset along x, force along z: rotation about y (inertia 0.2)
    assert me == pytest.approx([m, 1.0 / (1.0 / m + r * r / 0.2)], rel=tol.EXACT_REL)
    moment = np.array([0.0, 1.0, 0.0])
    assert np.allclose(W[0, 3:, 3:] @ moment, moment / inertia)
    assert np.allclose(W[0, :3, 3:] @ moment, -np.cross(rb[0], moment / inertia))
    assert np.allclose(W[0], W[0].T)
