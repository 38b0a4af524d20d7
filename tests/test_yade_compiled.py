"""The compiled step inside YADE (engine "compiled": contact step and leapfrog integration
in numba) against the numpy law with YADE's NewtonIntegrator (engine "python"), on the
three kinds of motion the studies use: blocks free to rotate about every axis (YADE's
aspherical Fincham integration), the Sacsayhuaman stones with blocked rotations ("xYZ",
YADE's spherical update) under a base excitation with a velocity jump, and a block
pushed by a force. Both engines do the same arithmetic, mostly in the same order: on
separate blocks the histories agree to round-off amplified by the contacts' stiffness
(``ENGINE_AGREEMENT_M``). The wall's stones touch along exactly coplanar faces, where a
round-off change of a position decides whether a contact exists, so its motion is
sensitive at round-off level whatever the engine: there the engines must differ by no more
than the model's own sensitivity, measured by running the reference engine again with the
stones' density changed by 1e-12 (relative).
"""
import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade
from drystone import runner
from drystone.postprocess import summary as summ

pytestmark = [requires_yade, pytest.mark.yade]


def _run(case: dict, outdir, name: str, engine: str, overrides=()):
    d = outdir / name
    runner.run_dict(case, outdir / f"{name}.toml", overrides=list(overrides), out_dir=d, quiet=True, engine=engine)
    return summ.load_histories(d)


def _both(case: dict, outdir, name: str):
    return _run(case, outdir, f"{name}_python", "python"), _run(case, outdir, f"{name}_compiled", "compiled")


def _agree(a, b, scale_m):
    assert len(a["t"]) == len(b["t"])
    np.testing.assert_allclose(b["pos"], a["pos"], rtol=0, atol=tol.ENGINE_AGREEMENT_M)
    np.testing.assert_allclose(b["quat"], a["quat"], rtol=0, atol=tol.ENGINE_AGREEMENT_M / scale_m)
    # the motion compared is not trivial
    assert np.abs(a["pos"] - a["pos"][0]).max() > 1e3 * tol.ENGINE_AGREEMENT_M


def test_rocking_blocks_free_in_every_direction(outdir):
    """Two slender blocks on the platform, tilted until one rocks, with a push: the
    aspherical integration (all rotations free)."""
    case = {"case": {"geometry": {"generator": "boxes_on_platform", "mu": 0.7, "damping": 0.3, "boxes": [
                {"id": 1, "center_xy": [0.0, 0.0], "size": [0.1, 0.15, 0.4]},
                {"id": 2, "center_xy": [0.5, 0.0], "size": [0.2, 0.2, 0.2]}]}},
            "stages": [{"type": "gravity", "duration": 0.3, "ramp": 0.1},
                       {"type": "tilt", "rate_deg_s": 20.0, "to_deg": 10.0, "towards": "+y"}],
            "forces": [{"block": 2, "force": [30.0, 20.0, 0.0], "start": 0.35, "end": 0.45}],
            "output": {"interval": 0.005}}
    a, b = _both(case, outdir, "rocking")
    _agree(a, b, 0.2)


def test_wall_with_blocked_rotations_under_excitation(outdir):
    """The 40-stone Sacsayhuaman section (side stones move in the y-z plane and turn about
    x; the others are free), a sine started as a displacement (a velocity jump of every
    stone), 0.6 s: the engines differ by as much as a round-off change of the model makes.
    Such a change either tips a joint's stick or slip at some step or does not (the
    divergence it leaves is bimodal: measured 4e-10 to 1.1e-6 m at t = 1 s), so the model's
    sensitivity is the largest over three (the density by 1e-12, K_n by 1e-9, mu by 1e-13
    relative, compiled engine)."""
    case = {"case": {"geometry": {"generator": "sacsayhuaman", "seed": 0}},
            "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2},
                       {"type": "excitation", "motion": "sine", "frequency_hz": 2.5, "amplitude": 3.0,
                        "duration": 0.6, "direction": "y", "start": "displacement"}],
            "output": {"interval": 0.01}}
    a, b = _both(case, outdir, "wall")
    perturbed = ["case.geometry.density=2300.0000000023", "case.geometry.kn=200000000.2",
                 "case.geometry.mu=0.40000000000004"]
    engines = np.abs(b["pos"] - a["pos"]).max()
    model = max(np.abs(_run(case, outdir, f"wall_perturbed{k}", "compiled", [o])["pos"] - b["pos"]).max()
                for k, o in enumerate(perturbed))
    motion = np.abs(a["pos"] - a["pos"][0]).max()
    assert motion > 1e-2  # the stones rock and slide (m)
    assert engines <= tol.ENGINE_SENSITIVITY_FACTOR * model
    assert engines < tol.ENGINE_DIVERGENCE_OF_MOTION * motion
