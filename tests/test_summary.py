"""summary.json building blocks on synthetic histories (no YADE)."""
import numpy as np
import pytest

from drystone.mechanics import rotations
from drystone.postprocess import summary as summ


def synthetic(n=200):
    """Block 2 on block 0 (fixed): touches its friction limit briefly at sample 50 (a
    jolt, no sliding), then slips for good from sample 120 and slides 5 cm."""
    t = np.linspace(0, 2, n)
    pos = np.zeros((n, 1, 3))
    pos[120:, 0, 0] = 0.05 * ((t[120:] - t[120]) / (t[-1] - t[120])) ** 2
    flags = np.zeros(n, bool)
    flags[50:52] = True
    flags[120:] = True
    ft = np.zeros((n, 3))
    ft[:, 0] = np.linspace(0, 10, n)
    h = {"t": t, "block_ids": np.array([2]), "pos": pos, "quat": np.tile([0, 0, 0, 1.0], (n, 1, 1)),
         "contacts": {"0-2": {"slipping": flags, "ft": ft, "fn": np.full(n, 20.0)}}}
    spec = {"output": {"contacts": [{"name": "0-2", "blocks": [0, 2]}]}}
    return spec, h


def test_slip_ignores_a_jolt_and_finds_the_onset():
    spec, h = synthetic()
    s = summ.slip(spec, h, "0-2", None)
    assert s["slip_time_s"] == pytest.approx(h["t"][120])
    assert s["slip_force_ratio"] == pytest.approx(h["contacts"]["0-2"]["ft"][120, 0] / 20.0)


def test_no_slip_without_sliding():
    spec, h = synthetic()
    h["pos"][:] = 0.0
    assert summ.slip(spec, h, "0-2", None)["slip_time_s"] is None


def test_relative_rotation_vectors():
    q0 = np.array([0, 0, 0, 1.0])
    q = np.array([0, 0, np.sin(0.25), np.cos(0.25)])  # 0.5 rad about z
    assert rotations.relative_rotation_vectors(q, q0) == pytest.approx([0, 0, 0.5])
    r = rotations.to_matrix(q)
    assert r @ np.array([1.0, 0, 0]) == pytest.approx([np.cos(0.5), np.sin(0.5), 0])


def test_block_faces_of_a_box():
    """A box has 6 quadrilateral faces."""
    from drystone.geometry import blockfile as bf
    from drystone.postprocess import snapshots
    faces = snapshots.block_faces(np.asarray(bf.box_vertices((0, 0, 0), (1, 2, 3)), float))
    assert len(faces) == 6 and all(len(f) == 4 for f in faces)


def test_contact_stability_against_the_central_difference_limit():
    """omega dt of the fastest contact mode against 2 (sqrt(1 + xi^2) - xi), xi the largest
    damping of the run's materials (0.8: limit 0.961)."""
    from drystone.postprocess.summary import contact_stability
    spec = {"materials": {"a": {"damping": 0.08}, "b": {"damping": 0.8}}}
    c = contact_stability(spec, {"max_contact_omega_dt": 0.33})
    assert c["limit"] == pytest.approx(2 * (np.sqrt(1.64) - 0.8)) and c["within"]
    assert not contact_stability(spec, {"max_contact_omega_dt": 1.2})["within"]
    assert contact_stability(spec, {}) is None
