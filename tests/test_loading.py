"""The load programme in the platform frame (drystone/loading.py)."""
import math

import numpy as np
import pytest

from drystone.loading import LoadProgramme, Stage

G = 9.81


def prog():
    return LoadProgramme([
        Stage("gravity", 0.0, 2.0, {"ramp": 1.0}),
        Stage("tilt", 2.0, 12.0, {"rate_deg_s": 1.0, "towards": [0, 1, 0]}),
        Stage("settlement", 12.0, 17.0, {"block": 3, "displacement": 0.05}),
        Stage("excitation", 17.0, 18.0, {"acc": np.array([0.0, 1.0, 2.0]), "dt": 0.5, "direction": [1, 0, 0]}),
    ], G)


def test_gravity_ramp_then_hold():
    p = prog()
    assert p.body_acceleration(0.5)[2] == pytest.approx(-G / 2)
    assert p.body_acceleration(1.5) == pytest.approx([0, 0, -G])


def test_tilt_rotates_gravity_towards_fall_direction():
    """At 10 deg towards +y: g_eff = g (sin 10, -cos 10) in (y, z); magnitude g."""
    p = prog()
    g = p.body_acceleration(12.0)
    assert p.tilt_deg(12.0) == pytest.approx(10.0)
    assert g == pytest.approx([0, G * math.sin(math.radians(10)), -G * math.cos(math.radians(10))])
    assert p.true_vertical(12.0) @ g == pytest.approx(-G)  # gravity is along the true vertical
    top = p.to_world(12.0, np.array([[0, 0, 1.0]]))[0]
    assert top[1] > 0 and top @ p.to_world(12.0, np.array([[0, 0, 1.0]]))[0] == pytest.approx(1.0)


def test_settlement_velocity():
    p = prog()
    assert p.imposed_velocities(13.0)[3] == pytest.approx([0, 0, -0.01])
    assert p.imposed_velocities(17.5)[3] == pytest.approx([0, 0, 0])


def test_base_acceleration_is_an_inertial_body_force():
    p = prog()
    assert p.base_acceleration(17.25) == pytest.approx([0.5, 0, 0])
    g = p.body_acceleration(17.25)
    assert g[0] == pytest.approx(-0.5)  # the block feels -a_base
