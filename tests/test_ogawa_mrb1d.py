"""The paper's 1D friction/impact model (drystone/studies/ogawa/mrb1d.py) against closed forms."""
import numpy as np
import pytest

import tolerances as tol
from drystone.studies.ogawa import mrb1d
from reference import sliding_block

G = mrb1d.G


def one_block(mu, m=2.0):
    return mrb1d.Model(np.array([m]), [(0, -1, mu * m * G)])


def test_constant_acceleration_below_friction_sticks():
    """a_g = 0.3 g < mu g = 0.4 g: the block moves with the base (u = 0 exactly)."""
    r = mrb1d.simulate(one_block(0.4), np.full(101, 0.3 * G), 0.01)
    assert np.abs(r.u).max() == 0.0
    assert r.sticking.all()


def test_constant_acceleration_above_friction_slides():
    """a_g = 0.6 g > mu g: relative acceleration -(a_g - mu g), u = -(a_g - mu g) t^2 / 2
    (Newmark is exact for constant acceleration: 1e-12)."""
    r = mrb1d.simulate(one_block(0.4), np.full(201, 0.6 * G), 0.01)
    assert r.u[:, 0] == pytest.approx(-0.5 * 0.2 * G * r.t ** 2, abs=tol.EXACT_ABS)


def test_sine_base_matches_independent_integration():
    """Sliding block under a 2 Hz, 1 m/s^2 sine (mu = 0.05): the history matches an
    independent explicit integration (step 1e-5 s) within 1 % of its peak. Newmark is
    first order at the stick/slip events (they fall inside a step): 1.5 % at 1e-3 s,
    0.4 % at 2.5e-4 s, hence records are integrated with sub-steps of 2.5e-4 s or less."""
    f, amp, mu = 2.0, 1.0, 0.05
    dt = 2.5e-4
    t = np.arange(0, 1.5 + dt / 2, dt)
    acc = -amp * np.sin(2 * np.pi * f * t)
    r = mrb1d.simulate(one_block(mu), acc, dt)
    ref = sliding_block(lambda x: -amp * np.sin(2 * np.pi * f * x), t, mu)
    assert np.abs(r.u[:, 0] - ref).max() < tol.MRB1D_REL * np.abs(ref).max()


def test_elastic_impact_conserves_momentum_and_energy():
    """Two frictionless blocks, 1 kg at 1 m/s hits 3 kg at rest (e = 1): momentum and
    kinetic energy conserved; velocities -0.5 and +0.5 m/s (1D elastic collision)."""
    model = mrb1d.Model(np.array([1.0, 3.0]), [], neighbours=[(0, 1)], restitution=1.0)
    r = mrb1d.simulate(model, np.zeros(51), 0.001, u0=[-0.01, 0.0], v0=[1.0, 0.0])
    v = r.v[-1]
    assert v == pytest.approx([-0.5, 0.5], abs=tol.EXACT_ABS)
    assert (model.mass * v).sum() == pytest.approx(1.0, abs=tol.EXACT_ABS)
    assert 0.5 * (model.mass * v ** 2).sum() == pytest.approx(0.5, abs=tol.EXACT_ABS)


def test_stack_slides_as_one_on_the_weak_interface():
    """Top block (mu 0.8 on the lower) on a bottom block (mu 0.2 on the base), a_g = 0.5 g:
    the stack slides on the base with relative acceleration -(0.5 - 0.2) g (the base
    carries both weights) and the top block sticks to the bottom one."""
    m = np.array([1.0, 1.0])
    model = mrb1d.Model(m, [(0, -1, 0.2 * 2 * G), (1, 0, 0.8 * G)])
    r = mrb1d.simulate(model, np.full(101, 0.5 * G), 0.01)
    assert r.u[:, 0] == pytest.approx(-0.5 * 0.3 * G * r.t ** 2, abs=tol.EXACT_ABS)
    assert r.u[:, 1] == pytest.approx(r.u[:, 0], abs=tol.EXACT_ABS)


def test_five_block_limits_follow_eq3():
    """Eq. 3: F10 = a t (h1 + h2) gamma mu10 etc.; masses 1.3, 1.3, 0.65, 1.3, 0.65 kg at
    2600 kg/m^3; the base carries the whole weight."""
    mu = dict.fromkeys(mrb1d.MU_KEYS, 0.5)
    model = mrb1d.five_blocks(mu)
    assert model.mass == pytest.approx([1.3, 1.3, 0.65, 1.3, 0.65])
    lim = {k: l for k, (_, _, l) in zip(mrb1d.MU_KEYS, model.interfaces)}
    assert lim["mu10"] + lim["mu20"] == pytest.approx(0.5 * model.mass.sum() * G)
    assert lim["mu41"] == pytest.approx(0.5 * 0.5 * 1.3 * G)


def test_five_blocks_density_free():
    """A pure-friction result does not depend on the density (module docstring)."""
    mu = {"mu10": 0.4, "mu20": 0.5, "mu31": 0.3, "mu41": 0.44, "mu42": 0.44, "mu52": 0.31}
    t = np.arange(0, 2, 0.005)
    acc = 6.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-t)
    r1 = mrb1d.simulate(mrb1d.five_blocks(mu, density=2600), acc, 0.005, substeps=2)
    r2 = mrb1d.simulate(mrb1d.five_blocks(mu, density=1000), acc, 0.005, substeps=2)
    assert r1.u == pytest.approx(r2.u, abs=tol.EXACT_ABS)
