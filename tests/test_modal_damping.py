"""The linearised model's contact damping (drystone.mechanics.modal.Assembly.damping) is the dynamic
law's: every mode of one block on its joint gets the damping ratio asked for."""
from __future__ import annotations

import numpy as np
import pytest

import tolerances as tol
from drystone.mechanics import modal
from drystone.geometry import blockfile as bf

RHO, KN, KT, G = 2300.0, 2e8, 1e8, 9.81


@pytest.mark.parametrize("xi", [0.05, 0.3, 0.8])
def test_every_mode_of_a_block_on_its_joint_gets_xi(xi):
    """One 0.2 x 0.2 x 0.4 m block, off the origin, resting on a fixed platform: the
    contact's damping matrix is built to give each of its modes xi exactly; gravity's
    geometric stiffness (-W h in rocking) is in K but not in the patch stiffness the
    dashpots are built on, which changes the rocking stiffness by W h / (K_n I) = 0.3 %
    and the rocking damping ratio by half that: tolerance 0.5 % of xi."""
    m = 0.2 * 0.2 * 0.4 * RHO
    d = m * G / (KN * 0.04)  # static overlap depth
    plat = np.array(bf.box_vertices((0, 0, -0.025), (2, 2, 0.05)))
    blk = np.array(bf.box_vertices((0.3, -0.2, 0.2 - d), (0.2, 0.2, 0.4)))
    asm = modal.Assembly([plat, blk], moving=[False, True], density=RHO, kn=KN, kt=KT,
                         gravity=np.array([0.0, 0.0, -G]))
    r = asm.modes(direction=(0, 1, 0))
    f, z, _ = asm.damped_modes(0.5 * (r["K"] + r["K"].T), asm.damping(xi), r["M"])
    assert len(f) == 6  # rocking x2, bouncing, sliding x2, twist about z (the twist spring)
    np.testing.assert_allclose(z, xi, rtol=tol.MODAL_DAMPING_RATIO_REL)
    undamped = np.sort(r["frequency_hz"])
    np.testing.assert_allclose(np.sort(f), undamped, rtol=tol.DAMPED_FREQUENCY_REL)  # |lambda| is the undamped frequency


def test_frequency_response_is_static_compliance_at_low_frequency():
    """Far below the first mode the base-acceleration transfer function is K^-1 M r."""
    m = 0.2 * 0.2 * 0.4 * RHO
    d = m * G / (KN * 0.04)
    plat = np.array(bf.box_vertices((0, 0, -0.025), (2, 2, 0.05)))
    blk = np.array(bf.box_vertices((0.0, 0.0, 0.2 - d), (0.2, 0.2, 0.4)))
    asm = modal.Assembly([plat, blk], moving=[False, True], density=RHO, kn=KN, kt=KT,
                         gravity=np.array([0.0, 0.0, -G]))
    r = asm.modes(direction=(0, 1, 0))
    K, M = 0.5 * (r["K"] + r["K"].T), r["M"]
    X = asm.frequency_response(K, asm.damping(0.3), M, [1e-3])[0]
    np.testing.assert_allclose(X.real, -np.linalg.solve(K, M @ asm.influence((0, 1, 0))),
                               rtol=tol.STATIC_COMPLIANCE_REL, atol=tol.ZERO_ABS)
