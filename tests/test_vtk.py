"""VTK output (drystone/postprocess/vtk.py) on a synthetic run: a cube translated and turned on a
platform, read back with the standard library's XML parser."""
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.postprocess import vtk


def fake_run(folder, dx, angle):
    """Platform (0) and a unit cube (1) centred at (0, 0, 0.5); sample 1 moves the cube by
    dx and turns it by ``angle`` rad about z."""
    folder.mkdir()
    blocks = [{"id": 0, "role": "platform", "material": "m", "vertices": bf.box_vertices((0, 0, -0.05), (3, 3, 0.1))},
              {"id": 1, "role": "free", "material": "m", "vertices": bf.box_vertices((0, 0, 0.5), (1, 1, 1))}]
    (folder / "geometry.json").write_text(json.dumps({"blocks": blocks}))
    (folder / "spec.json").write_text(json.dumps({"gravity": 9.81, "stages": [
        {"kind": "gravity", "start": 0.0, "end": 1.0, "params": {"ramp": 0.5}}]}))
    q0 = np.array([[0.0, 0.0, 0.0, 1.0]])  # (x, y, z, w) as drystone.mechanics.rotations
    q1 = np.array([[0.0, 0.0, np.sin(angle / 2), np.cos(angle / 2)]])
    c0 = np.array([[0.0, 0.0, 0.5]])
    np.savez(folder / "histories.npz", t=np.array([0.0, 1.0]), tilt_deg=np.zeros(2), block_ids=np.array([1]),
             pos0=c0, quat0=q0, pos=np.stack([c0, c0 + dx]), quat=np.stack([q0, q1]))
    return np.asarray(blocks[1]["vertices"])


def piece(path):
    p = ET.parse(path).getroot().find("PolyData/Piece")
    arr = lambda el: np.array(el.text.split(), float)  # noqa: E731
    pts = arr(p.find("Points/DataArray")).reshape(-1, 3)
    cells = {d.get("Name"): arr(d) for d in p.find("CellData")}
    offsets = arr(p.find("Polys/DataArray[@Name='offsets']")).astype(int)
    return pts, cells, offsets


def test_moved_cube_is_written_where_it_is(tmp_path):
    dx = np.array([0.3, -0.1, 0.0])
    angle = 0.4
    v = fake_run(tmp_path / "run", dx, angle)
    pvd = vtk.write(tmp_path / "run")
    steps = ET.parse(pvd).getroot().findall("Collection/DataSet")
    assert [float(s.get("timestep")) for s in steps] == [0.0, 1.0]
    pts, cells, offsets = piece(pvd.parent / steps[1].get("file"))
    assert len(offsets) == 12 and np.all(np.diff(np.concatenate([[0], offsets])) == 4)  # two boxes, quads
    cube = pts[np.repeat(cells["block_id"] == 1, 4)]
    rz = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    expected = (v - [0, 0, 0.5]) @ rz.T + [0, 0, 0.5] + dx
    # every written corner is a corner of the moved, turned cube, and all 8 corners appear
    dist = np.linalg.norm(cube[:, None, :] - expected[None], axis=2)
    assert dist.min(axis=1).max() < tol.VTK_COORDINATE_M and dist.min(axis=0).max() < tol.VTK_COORDINATE_M
    assert cells["displacement_m"][cells["block_id"] == 1] == pytest.approx(np.linalg.norm(dx))
    assert np.all(cells["moving"][cells["block_id"] == 0] == 0) and np.all(cells["displacement_m"][:6] == 0)


def test_not_a_run_folder(tmp_path):
    (tmp_path / "x").mkdir()
    for f in ("spec.json", "geometry.json"):
        (tmp_path / "x" / f).write_text("{}")
    with pytest.raises(FileNotFoundError, match="histories.npz"):
        vtk.write(tmp_path / "x")
    assert not (tmp_path / "x" / "vtk").exists()  # nothing written
