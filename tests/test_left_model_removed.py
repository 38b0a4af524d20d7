"""Stones that leave the model are taken out of the scene when they leave.

Two boxes on a 2 m platform; box 2, near the edge, is pushed off it (2 W along +x) and falls
below the platform's underside: it leaves the model (drystone/mechanics/stability.py
``ModelRegion``) at a recorded sample, is listed with that time (run_info.json and
summary.json ``run.left_model``), and from then on is neither integrated (its position
stays where it left, exactly: its velocities are zeroed and its DOFs blocked) nor in any
contact, nor carries kinetic or potential energy; the kinetic energy it carried out is
``removed_kinetic``, and the balance B = kinetic + elastic + dissipated + removed_kinetic -
work_loads of the remaining wall closes within leapfrog's bound (tests/test_energy.py's).
The VTK set stays within the model region (before: the box fell on for as long as the
run lasted). Both engines of the project's law; the stock YADE law blocks the stone the
same way (its energies are not accounted)."""
from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

import tolerances as tol
from conftest import requires_yade
from drystone.mechanics import stability
from drystone.postprocess import summary as summ
from test_energy import bound

RHO, SIZE = 2300.0, (0.2, 0.2, 0.2)
W = RHO * float(np.prod(SIZE)) * 9.81


def push_off_case():
    boxes = [{"id": 1, "center_xy": [0.0, 0.0], "size": list(SIZE)},
             {"id": 2, "center_xy": [0.85, 0.0], "size": list(SIZE)}]
    return {"case": {"name": "push_off", "geometry": {"generator": "boxes_on_platform", "damping": 0.0,
                                                      "density": RHO, "boxes": boxes}},
            "stages": [{"type": "gravity", "duration": 0.2, "ramp": 0.1}, {"type": "rest", "duration": 0.6}],
            "forces": [{"block": 2, "force": [2.0 * W, 0.0, 0.0], "start": 0.2, "end": 0.45}],
            "output": {"interval": 0.005}}


@pytest.fixture(scope="module", params=["compiled", "python"])
def pushed_off(request, tmp_path_factory):
    """The run, with each engine of the project's law (the compiled step; numpy forces with
    YADE's integrator): both take the stone out."""
    from drystone import runner
    d = tmp_path_factory.mktemp("push_off")
    out = d / "run"
    s = runner.run_dict(push_off_case(), d / "push_off.toml", out_dir=out, quiet=True, engine=request.param)
    return s, summ.load_histories(out), out


@requires_yade
@pytest.mark.yade
def test_a_stone_pushed_off_the_edge_is_taken_out_where_it_left(pushed_off):
    s, h, out = pushed_off
    info = json.loads((out / "run_info.json").read_text())
    spec = json.loads((out / "spec.json").read_text())
    (gone,) = info["left_model"]
    assert gone["block"] == 2 and gone["where"].startswith("below")
    (listed,) = s["run"]["left_model"]["blocks"]
    assert listed["block"] == 2 and listed["time_s"] == pytest.approx(gone["time_s"], rel=tol.EXACT_REL)
    assert s["run"]["left_model"]["count"] == 1 and "taken out" in s["run"]["left_model"]["taken_out"]
    assert not info["stopped_early"]  # box 1 is still in the model: the run goes on
    k = int(np.flatnonzero(np.isclose(h["t"], gone["time_s"], rtol=tol.EXACT_REL, atol=0.0))[0])
    assert k < len(h["t"]) - 20  # many samples after it left
    j = int(np.flatnonzero(h["block_ids"] == 2)[0])
    # not integrated from then on: it stays where it left (velocities zeroed, DOFs blocked: exact)
    assert np.array_equal(h["pos"][k:, j], np.repeat(h["pos"][k:k + 1, j], len(h["t"]) - k, axis=0))
    assert np.array_equal(h["pos"][k, j], np.asarray(gone["position_m"]))
    assert np.array_equal(h["quat"][k:, j], np.repeat(h["quat"][k:k + 1, j], len(h["t"]) - k, axis=0))
    assert not np.any(h["vel"][k + 1:, j]) and not np.any(h["angvel"][k + 1:, j])
    # it carries no energy from then on: the kinetic energy is box 1's (at rest), and the
    # kinetic energy it carried out is recorded once, at its value at the sample it left
    assert h["removed_kinetic"][k] == 0.0 and h["removed_kinetic"][k + 1] == pytest.approx(h["kinetic"][k], rel=1e-6)
    assert h["removed_kinetic"][-1] == h["removed_kinetic"][k + 1]
    assert h["kinetic"][k + 1:].max() < 1e-3 * h["removed_kinetic"][-1]
    g = np.asarray(h["g_eff"][-1])
    m1 = float(h["mass"][1 - j])
    assert h["potential"][-1] == pytest.approx(-m1 * float(h["pos"][-1, 1 - j] @ g), rel=1e-3)  # box 1's only
    # the balance of what remains closes (tests/test_energy.py's bound); without the energy
    # carried out it would be off by that whole kinetic energy
    err = np.abs(summ.balance_history(h))
    assert err.max() <= bound(h, spec["dt"], SIZE)
    assert h["removed_kinetic"][-1] > 2 * bound(h, spec["dt"], SIZE)
    assert s["energy"]["balance_error_J"] == pytest.approx(err.max(), rel=tol.EXACT_REL)
    assert s["run"]["left_model"]["removed_kinetic_J"] == pytest.approx(h["removed_kinetic"][-1], rel=tol.EXACT_REL)
    assert s["energy"]["final"]["removed_kinetic_J"] == pytest.approx(h["removed_kinetic"][-1], rel=tol.EXACT_REL)


@requires_yade
@pytest.mark.yade
def test_postprocess_of_a_run_where_a_stone_left_stays_bounded(pushed_off):
    """The VTK set's points stay within the model region enlarged by one stone (the one
    that left is drawn where it left, in the platform frame)."""
    from drystone.postprocess import vtk
    _, h, out = pushed_off
    spec = json.loads((out / "spec.json").read_text())
    region = stability.ModelRegion.from_blocks(spec["blocks"])
    pvd = vtk.write(out, every=20, world=False)
    files = sorted(pvd.parent.glob("*.vtu"))
    assert len(files) >= 8
    for f in files:
        p = meshio.read(f).points
        assert np.all(p >= region.lo - max(SIZE)) and np.all(p <= region.hi + max(SIZE)), f.name
    # the block table's maxima are the remaining stone's, bounded (box 1 barely moved)
    assert h["pos"][:, :, 2].min() > region.lo[2] - max(SIZE)
