"""The compiled contact step (drystone/mechanics/contact_step.py) against the numpy law it replaces,
and its leapfrog integrator against closed forms (no YADE).

A 3-course running-bond wall is pressed into its joints, given small random rotations and
velocities (seeded), and both steps are driven through 40 steps along the same motion, so
that contacts form, stick, slip and carry shear history: forces, torques, stored shear,
elastic energy and the energy balance's terms (damping wrenches, slip work) agree to
``NUMERICAL_REL`` of their scale (the two differ only in the order
of floating-point operations). The integrator is checked on motions it integrates exactly
(uniform acceleration, torque-free spin) and against Fincham's scheme's invariants.
"""
import numba
import numpy as np
import pytest

import tolerances as tol
from drystone.mechanics import contact as law
from drystone.mechanics import contact_step as cs
from drystone.mechanics import integration, rotations
from drystone.mechanics.contact_rows import PARALLEL_ROWS
from drystone.geometry import polyhedron as ph
from drystone.geometry import running_bond


def _wall(seed=0, courses=3, per_course=4):
    blocks = running_bond.make(courses=courses, per_course=per_course, length=per_course * 1.0, height=courses * 0.5,
                               thickness=0.5)["blocks"]
    rng = np.random.default_rng(seed)
    nb = len(blocks)
    verts = [np.asarray(b["vertices"], float) for b in blocks]
    cen = np.array([ph.volume_centroid(v)[1] for v in verts])
    local = [v - c for v, c in zip(verts, cen)]
    moving = np.array([b["role"] == "free" for b in blocks])
    mass = np.where(moving, [2300.0 * ph.volume_centroid(v)[0] for v in verts], np.inf)
    inertia = np.ones((nb, 3)) * 50.0
    pos = cen.copy()
    # press each course into the one below and shift sideways a little, so joints overlap
    pos[moving, 2] -= 2e-4 * (1 + rng.random(moving.sum()))
    pos[moving, 1] += 1e-4 * rng.standard_normal(moving.sum())
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (nb, 1))
    quat[moving, :3] = 1e-4 * rng.standard_normal((moving.sum(), 3))
    quat /= np.linalg.norm(quat, axis=1)[:, None]
    vel = np.where(moving[:, None], 0.01 * rng.standard_normal((nb, 3)), 0.0)
    angvel = np.where(moving[:, None], 0.02 * rng.standard_normal((nb, 3)), 0.0)
    return local, mass, inertia, pos, quat, vel, angvel, moving


MAT = {"kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}


@pytest.mark.parametrize("seed,area_scaling", [(0, False), (1, False), (0, True)])
def test_compiled_forces_equal_numpy_law(seed, area_scaling):
    """``area_scaling``: the opt-in law's carried force scaled where the patch shrinks
    (contact.carried_share, law penalty_coulomb_area), the same in both steps."""
    local, mass, inertia, pos, quat, vel, angvel, moving = _wall(seed)
    nb = len(mass)
    joint = {"mu": 0.2, "damping": 0.3}
    props = law.pair_properties(MAT, MAT)
    jprops = law.pair_properties(MAT, MAT, joint)

    def pair_props(a, b):
        return jprops if {a, b} == {1, 5} else props

    ref = cs.NumpyStep(pair_props, mass, local, "native", inertia, area_scaling=area_scaling)
    table = np.array([[[props[k] for k in ("kn", "kt", "mu", "damping")]]])
    fast = cs.CompiledStep(mass, inertia, local, np.zeros(nb, int), table,
                           {(1, 5): [jprops[k] for k in ("kn", "kt", "mu", "damping")]}, area_scaling=area_scaling)
    rel = tol.AREA_SCALED_REL if area_scaling else tol.NUMERICAL_REL
    shrank = 0  # contacts carrying a shear force whose area shrank (their force scaled, with area_scaling)
    dt = 2e-4
    slipped = stuck = 0
    twisted = 0.0  # the largest twisting moment compared, N m
    slip_work = [0.0, 0.0]  # the energy balance's slip work (J), numpy and compiled
    for step in range(40):
        rot = rotations.to_matrix(quat)
        st = (pos, vel, angvel, rot)
        before = dict(ref._shear)
        F0, T0 = ref.forces(ref.native_geometry(st), st, dt)
        if area_scaling:
            shrank += sum(1 for k, v in ref._shear.items()
                          if k in before and before[k][4] > v[4] and np.any(before[k][:3] != 0.0))
        F1, T1 = fast.forces(pos, rot, vel, angvel, dt)
        fscale = np.abs(F0).max()
        tscale = np.abs(T0).max()
        assert fscale > 0
        np.testing.assert_allclose(F1, F0, rtol=0, atol=rel * fscale)
        np.testing.assert_allclose(T1, T0, rtol=0, atol=rel * tscale)
        a, b = ref.state, fast.state
        np.testing.assert_array_equal(a.id1, b.id1)
        np.testing.assert_array_equal(a.slipping, b.slipping)
        np.testing.assert_allclose(b.shear, a.shear, rtol=0, atol=rel * fscale)
        assert fast.elastic[1] == pytest.approx(ref.elastic[1], rel=rel)
        # the twisting moments about n (contact.twist_spring), in the contacts' order
        mt0 = np.array([v[3] for v in ref._shear.values()])
        np.testing.assert_allclose(fast.shear_store[:, 3], mt0, rtol=0, atol=rel * tscale)
        twisted = max(twisted, float(np.abs(mt0).max()))
        # the energy balance's terms (drystone/mechanics/energy.py): damping wrenches on each body, slip work
        np.testing.assert_allclose(fast.last["Fd"], ref.last["Fd"], rtol=0, atol=rel * fscale)
        np.testing.assert_allclose(fast.last["Td"], ref.last["Td"], rtol=0, atol=rel * tscale)
        slip_work[0] += ref.last["slip"]
        slip_work[1] += fast.last["slip"]
        slipped += int(a.slipping.sum())
        stuck += int((~a.slipping).sum())
        # move along a prescribed path (the same for both laws)
        pos = pos + vel * dt
        quat = rotations.multiply(np.c_[0.5 * angvel * dt, np.ones(nb)], quat)
        quat /= np.linalg.norm(quat, axis=1)[:, None]
        vel = vel * 0.97
    assert slipped > 0 and stuck > 0  # both branches of the law were compared
    assert shrank > 0 or not area_scaling  # and the scaling of the carried force
    assert twisted > tol.NUMERICAL_REL * tscale  # and twisting moments
    assert slip_work[0] > 0 and slip_work[1] == pytest.approx(slip_work[0], rel=rel)


def _one(mass, inertia, blocked="", moving=True):
    lin, rot_ = integration.free_directions(blocked, moving)
    aspherical = np.array([moving and not any(c in blocked for c in "XYZ")])
    return (np.array([mass]), np.array([inertia], float), lin[None], rot_[None], aspherical,
            np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)),
            np.array([[0.0, 0.0, 0.0, 1.0]]), np.eye(3)[None].copy())


def test_integrate_uniform_acceleration_is_leapfrog_exact():
    m, I, lin, rf, asph, pos, vel, angvel, angmom, quat, rot = _one(2.0, [1.0, 2.0, 3.0], blocked="y")
    g = np.array([0.0, -9.81, -9.81])
    F = np.array([[4.0, 4.0, 0.0]])
    dt, n = 1e-3, 500
    for _ in range(n):
        integration.integrate(dt, g, F, np.zeros((1, 3)), m, I, lin, rf, asph, pos, vel, angvel, angmom, quat, rot, 1)
    # leapfrog from rest: v = n a dt, x = a dt^2 n (n + 1) / 2 (exact for a constant force)
    a = np.array([2.0, 0.0, -9.81])  # y blocked
    np.testing.assert_allclose(vel[0], n * a * dt, rtol=tol.EXACT_REL)
    np.testing.assert_allclose(pos[0], a * dt * dt * n * (n + 1) / 2, rtol=tol.EXACT_REL)


def _spin(dt, t_end=2.5):
    """Torque-free spin of an asymmetric body: (final angular momentum, energy error)."""
    m, I, lin, rf, asph, pos, vel, angvel, angmom, quat, rot = _one(1.0, [1.0, 2.0, 3.0])
    L0 = np.array([0.3, 1.0, 0.05])
    angmom[0] = L0
    e0 = 0.5 * np.sum(L0 * L0 / I[0])
    for _ in range(int(round(t_end / dt))):
        integration.integrate(dt, np.zeros(3), np.zeros((1, 3)), np.zeros((1, 3)), m, I, lin, rf, asph, pos, vel, angvel,
                              angmom, quat, rot, 1)
    assert abs(np.linalg.norm(quat[0]) - 1) < 10 * tol.FEW_ULP_REL
    wl = rot[0].T @ angvel[0]  # body-frame angular velocity at the last half step
    return angmom[0].copy(), 0.5 * np.sum(I[0] * wl * wl) / e0 - 1


def test_integrate_torque_free_spin_converges():
    """Fincham's scheme (all rotations free, aspherical): without torque the angular
    momentum is conserved exactly, and the energy error of the orientation's drift is
    first order in dt, as in YADE's NewtonIntegrator that this reproduces (halving dt
    halves it; 1.5-2.5 allows for the next order). The scheme is checked step for step
    against YADE's in tests/test_yade_compiled.py."""
    L1, e1 = _spin(1e-3)
    L2, e2 = _spin(5e-4)
    np.testing.assert_allclose(L1, [0.3, 1.0, 0.05], rtol=tol.EXACT_REL)
    assert abs(e1) > 0
    assert tol.FIRST_ORDER_RATIO_MIN < e1 / e2 < tol.FIRST_ORDER_RATIO_MAX


def test_integrate_blocked_rotation_spins_about_the_free_axis():
    """A body with rotations blocked about y and z (the Sacsayhuaman stones' "xYZ"):
    w += dt M / I on x only, and the orientation turns by |w| dt per step about x."""
    m, I, lin, rf, asph, pos, vel, angvel, angmom, quat, rot = _one(1.0, [2.0, 2.0, 2.0], blocked="xYZ")
    T = np.array([[1.0, 5.0, 5.0]])
    dt, n = 1e-3, 1000
    for _ in range(n):
        integration.integrate(dt, np.zeros(3), np.zeros((1, 3)), T, m, I, lin, rf, asph, pos, vel, angvel, angmom, quat,
                              rot, 1)
    assert angvel[0, 1] == 0 and angvel[0, 2] == 0
    np.testing.assert_allclose(angvel[0, 0], n * dt * 0.5, rtol=tol.EXACT_REL)
    angle = 0.5 * dt * dt * n * (n + 1) / 2  # sum of w_k dt
    np.testing.assert_allclose(2 * np.arctan2(quat[0, 0], quat[0, 3]), angle, rtol=tol.CHAINED_ULP_REL * n)


def test_non_moving_body_moves_with_its_velocity():
    """A settling block (non-moving, imposed velocity) is carried, never accelerated."""
    m, I, lin, rf, asph, pos, vel, angvel, angmom, quat, rot = _one(np.inf, [1.0, 1.0, 1.0], moving=False)
    vel[0] = [0.0, 0.0, -0.01]
    for _ in range(100):
        integration.integrate(1e-3, np.array([0.0, 0.0, -9.81]), np.ones((1, 3)), np.ones((1, 3)), m, I, lin, rf, asph, pos,
                              vel, angvel, angmom, quat, rot, 1)
    np.testing.assert_allclose(vel[0], [0.0, 0.0, -0.01])
    np.testing.assert_allclose(pos[0], [0.0, 0.0, -1e-3], rtol=tol.EXACT_REL)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba runs one thread here")
def test_two_threads_give_the_one_thread_history_bit_for_bit():
    """The contact search shares the listed pairs among threads, each pair clipped with the
    same arithmetic into its own row, the rows then gathered in the list's order by one
    thread (drystone/mechanics/neighbours.py, ``search``), and the damping solves one range
    of contacts per thread (contact.damping_wrenches_warm); the sums on the bodies stay on
    one thread in the contacts' order. A run on 2 threads is the run on 1 by construction,
    so its history is compared exactly (a wall of 16 courses of 18 stones pressed into its
    joints, 5 x 20 steps of ``advance`` under gravity: more shapes, bodies and contacts
    than ``PARALLEL_ROWS``, below which every kernel stays on the calling thread)."""
    hist = []
    for threads in (1, 2):
        local, mass, inertia, pos, quat, vel, angvel, moving = _wall(0, courses=16, per_course=18)
        nb = len(mass)
        table = np.array([[[law.pair_properties(MAT, MAT)[k] for k in ("kn", "kt", "mu", "damping")]]])
        step = cs.CompiledStep(mass, inertia, local, np.zeros(nb, int), table, threads=threads)
        rot = rotations.to_matrix(quat)
        free = np.where(moving[:, None], 1.0, 0.0) * np.ones((nb, 3))
        motion = (np.where(moving, mass, 1.0), inertia, free, free, moving.copy(), np.zeros((nb, 3)), quat)
        g = np.tile([0.0, 0.0, -9.81], (20, 1))
        rows = []
        for _ in range(5):
            done, F, T, _ = step.advance(pos, rot, vel, angvel, 2e-4, g, np.zeros((nb, 3)), motion)
            assert done == len(g)
            rows.append(np.concatenate([pos.ravel(), quat.ravel(), vel.ravel(), angvel.ravel(), F.ravel(), T.ravel(),
                                        step.shear_store.ravel(), step.energy]))
        assert min(len(step.keys), nb) >= PARALLEL_ROWS  # the threads' branches run
        hist.append(rows)
    for two, one in zip(*hist):  # (the contacts, so the shear rows, change between samples)
        np.testing.assert_array_equal(two, one)


def test_python_calls_of_the_step_type_no_argument_in_python(monkeypatch):
    """Each call of ``CompiledStep.forces``, ``peek`` and ``advance`` types its arguments in
    numba's C dispatcher, never through numba's Python ``typeof``: a tuple of more than four
    arrays (the neighbour list's and the search's state passed as two tuples) went through it
    at every call in numba 0.58 (its type fingerprint outgrows 40 bytes and never hits numba's
    cache), 0.4 ms a call, more than a small wall's step (the note above
    ``contact_step._advance``). After a first call of each (which may type and
    compile), further calls must not reach ``typeof_pyval``. ``forces`` and ``peek`` run the kernel
    ``advance`` runs (``_advance`` asked for no step): one compiled signature for the three."""
    local, mass, inertia, pos, quat, vel, angvel, moving = _wall(0, courses=2, per_course=2)
    nb = len(mass)
    table = np.array([[[law.pair_properties(MAT, MAT)[k] for k in ("kn", "kt", "mu", "damping")]]])
    step = cs.CompiledStep(mass, inertia, local, np.zeros(nb, int), table)
    rot = rotations.to_matrix(quat)
    free = np.where(moving[:, None], 1.0, 0.0) * np.ones((nb, 3))
    motion = (np.where(moving, mass, 1.0), inertia, free, free, moving.copy(), np.zeros((nb, 3)), quat)
    g = np.tile([0.0, 0.0, -9.81], (3, 1))

    def calls():
        step.forces(pos, rot, vel, angvel, 2e-4)
        step.peek(pos, rot, vel, angvel, 2e-4)
        step.advance(pos, rot, vel, angvel, 2e-4, g, np.zeros((nb, 3)), motion)

    before = set(cs._advance.signatures)
    calls()
    assert len(set(cs._advance.signatures) - before) <= 1
    typed = []

    def recording(kernel):
        def typeof_pyval(val):
            typed.append((kernel.__name__, type(val).__name__))
            return original(val)
        original = kernel.typeof_pyval
        return typeof_pyval

    monkeypatch.setattr(cs._advance, "typeof_pyval", recording(cs._advance), raising=False)
    for _ in range(3):
        calls()
    assert typed == []
