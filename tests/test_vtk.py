"""VTK output (drystone/postprocess/vtk.py) on synthetic runs whose motion is known in closed
form: a cube translated and turned on a platform, a stone of two parts, a tilted platform.
Every written file is read back with meshio (exactly what was meant to be written) and,
independently of meshio, with the standard library (XML structure, base64 + zlib arrays
as VTK's XML readers decode them). The Python VTK library is not installed here: ParaView's
reading rests on that structure (VTK XML UnstructuredGrid 0.1, UInt32 headers,
vtkZLibDataCompressor, polygon cells of type 7) and on meshio's writer."""
import base64
import json
import struct
import xml.etree.ElementTree as ET
import zlib

import meshio
import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.postprocess import runfolder, snapshots, vtk

GRAVITY = {"type": "gravity", "start": 0.0, "end": 1.0, "params": {"ramp": 0.5}}


def rz(angle):
    return np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])


def fake_run(folder, dx, angle, times=(0.0, 1.0), stages=(GRAVITY,), cube_parts=False):
    """Platform (0) and a unit cube (1) centred at c0 = (0, 0, 0.5) (with ``cube_parts``: a
    stone of two 0.5 m x 1 m x 1 m parts); sample k moves the cube by k dx and turns it by k
    ``angle`` rad about z through its centre. Returns the cube's initial points."""
    folder.mkdir()
    cube = {"id": 1, "role": "free", "material": "m"}
    if cube_parts:
        cube["parts"] = [bf.box_vertices((-0.25, 0, 0.5), (0.5, 1, 1)), bf.box_vertices((0.25, 0, 0.5), (0.5, 1, 1))]
    else:
        cube["vertices"] = bf.box_vertices((0, 0, 0.5), (1, 1, 1))
    blocks = [{"id": 0, "role": "platform", "material": "m", "vertices": bf.box_vertices((0, 0, -0.05), (3, 3, 0.1))},
              cube]
    (folder / "geometry.json").write_text(json.dumps({"blocks": blocks}))
    (folder / "spec.json").write_text(json.dumps({"gravity": 9.81, "stages": list(stages)}))
    (folder / "summary.json").write_text(json.dumps({"name": folder.name, "run": {"steps": len(times),
                                                                                 "simulated_time_s": times[-1]}}))
    k = np.arange(len(times))
    c0 = np.array([[0.0, 0.0, 0.5]])
    q = np.zeros((len(times), 1, 4))  # (x, y, z, w) as drystone.mechanics.rotations
    q[:, 0, 2], q[:, 0, 3] = np.sin(k * angle / 2), np.cos(k * angle / 2)
    np.savez(folder / "histories.npz", t=np.array(times, float), tilt_deg=np.zeros(len(times)),
             block_ids=np.array([1]), pos0=c0, quat0=q[0], pos=c0 + k[:, None, None] * np.asarray(dx, float),
             quat=q)
    return snapshots.stone_geometry([cube])[1][0]


def samples(pvd):
    """(time, file) of every DataSet of a .pvd."""
    root = ET.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    return [(float(d.get("timestep")), pvd.parent / d.get("file")) for d in root.findall("Collection/DataSet")]


def cube_rows(mesh, n_platform=8):
    """The cube's point rows (after the platform's 8 corners: blocks are written in id order)."""
    return slice(n_platform, len(mesh.points))


def cells_of(mesh, name):
    return np.concatenate(mesh.cell_data[name])


def test_displacement_and_rotation_are_the_rigid_motion(tmp_path):
    """Vertex displacement x(t) - x(0) = (Rz(a) - I)(v - c0) + dx, rotation (0, 0, a),
    centroid displacement dx; the platform's are zero; exact up to round-off."""
    dx, angle = np.array([0.3, -0.1, 0.02]), 0.4
    v = fake_run(tmp_path / "run", dx, angle)
    (t0, f0), (t1, f1) = samples(vtk.write(tmp_path / "run"))
    m = meshio.read(f1)
    expected = (v - [0, 0, 0.5]) @ rz(angle).T + [0, 0, 0.5] + dx
    assert m.points[cube_rows(m)] == pytest.approx(expected, abs=tol.EXACT_ABS)
    assert m.point_data["displacement"][cube_rows(m)] == pytest.approx(expected - v, abs=tol.EXACT_ABS)
    assert np.all(m.point_data["displacement"][:8] == 0)
    block, moving = cells_of(m, "block_id"), cells_of(m, "moving")
    assert list(block) == [0] * 6 + [1] * 6 and list(moving) == [0] * 6 + [1] * 6
    assert cells_of(m, "rotation")[block == 1] == pytest.approx(np.tile([0, 0, angle], (6, 1)), abs=tol.EXACT_ABS)
    assert cells_of(m, "centroid_displacement")[block == 1] == pytest.approx(np.tile(dx, (6, 1)), abs=tol.EXACT_ABS)
    assert np.all(cells_of(m, "rotation")[block == 0] == 0)
    assert np.all(cells_of(m, "centroid_displacement")[block == 0] == 0)
    m0 = meshio.read(f0)  # the first sample is the initial geometry
    assert np.all(m0.point_data["displacement"] == 0) and np.all(cells_of(m0, "rotation") == 0)
    assert {m.cells[0].type} == {"polygon"} and len(cells_of(m, "block_id")) == 12


def test_every_file_reads_back_exactly_and_the_pvd_lists_them(tmp_path):
    """Every file meshio reads back holds exactly the mesh built for it (points, cells,
    arrays, bit for bit); the .pvd lists every written file, in order, with its sample's
    time (s); ``every`` 2 over 5 samples writes samples 0, 2, 4, over 4 samples 0, 2 and the last."""
    for n, rows in ((5, [0, 2, 4]), (4, [0, 2, 3])):
        times = list(np.linspace(0.0, 0.7, n) + 0.013)
        fake_run(tmp_path / f"run{n}", [0.1, 0.05, 0.0], 0.3, times=times)
        pvd = vtk.write(tmp_path / f"run{n}", every=2)
        listed = samples(pvd)
        assert [t for t, _ in listed] == [times[i] for i in rows]
        assert sorted(f.name for _, f in listed) == sorted(p.name for p in pvd.parent.glob("*.vtu"))
        blocks = json.loads((tmp_path / f"run{n}" / "geometry.json").read_text())["blocks"]
        topo = vtk.Topology(blocks)
        frames = snapshots.frames_at(tmp_path / f"run{n}", [times[i] for i in rows])
        for (t, f), frame in zip(listed, frames):
            want, got = vtk.sample_mesh(topo, frame, {1}, snapshots.stone_centroids(blocks)), meshio.read(f)
            assert frame.t == t
            assert np.array_equal(got.points, want.points)
            assert [(c.type, c.data.tolist()) for c in got.cells] == [(c.type, c.data.tolist()) for c in want.cells]
            assert got.point_data.keys() == want.point_data.keys() and got.cell_data.keys() == want.cell_data.keys()
            for k in want.point_data:
                assert np.array_equal(got.point_data[k], want.point_data[k])
            for k in want.cell_data:
                assert len(got.cell_data[k]) == len(want.cell_data[k])
                for a, b in zip(got.cell_data[k], want.cell_data[k]):
                    assert a.dtype == b.dtype and np.array_equal(a, b)


def _decode(array, header_type="UInt32"):
    """A DataArray of format="binary" compressed with zlib, as VTK's reader decodes it: a
    base64 header (number of blocks, block size, last block size, each compressed size)
    and then the base64 of the compressed blocks."""
    fmt = {"UInt32": "I", "UInt64": "Q"}[header_type]
    size = struct.calcsize(fmt)
    text = array.text.strip()
    first = base64.b64decode(text[:4 * -(-3 * size // 3)])  # enough for the block count
    nblocks = struct.unpack("<" + fmt, first[:size])[0]
    hlen = 4 * -(-(3 + nblocks) * size // 3)
    head = struct.unpack(f"<{3 + nblocks}{fmt}", base64.b64decode(text[:hlen])[:(3 + nblocks) * size])
    raw = base64.b64decode(text[hlen:])
    out, pos = b"", 0
    for csize in head[3:]:
        out += zlib.decompress(raw[pos:pos + csize])
        pos += csize
    dtype = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "<u1"}[array.get("type")]
    return np.frombuffer(out, dtype)


def test_files_have_the_vtk_xml_structure(tmp_path):
    """The .vtu read without meshio: a VTK XML UnstructuredGrid piece with the point and cell
    counts, polygon cells (VTK type 7) with offsets, the four cell arrays and the point
    array with their component counts; decoded arrays equal what meshio reads."""
    fake_run(tmp_path / "run", [0.3, 0.0, 0.0], 0.2, cube_parts=True)
    _, f = samples(vtk.write(tmp_path / "run"))[1]
    root = ET.parse(f).getroot()
    assert root.tag == "VTKFile" and root.get("type") == "UnstructuredGrid" and root.get("byte_order") == "LittleEndian"
    assert root.get("compressor") == "vtkZLibDataCompressor"
    header = root.get("header_type", "UInt32")
    piece = root.find("UnstructuredGrid/Piece")
    m = meshio.read(f)
    assert int(piece.get("NumberOfPoints")) == len(m.points) == 8 + 16  # platform, the stone's two parts
    assert int(piece.get("NumberOfCells")) == 6 + 12
    arrays = {a.get("Name"): a for a in piece.iter("DataArray")}
    assert np.array_equal(_decode(arrays["Points"], header).reshape(-1, 3), m.points)
    assert np.all(_decode(arrays["types"], header) == 7)
    conn, offs = _decode(arrays["connectivity"], header), _decode(arrays["offsets"], header)
    assert np.array_equal(offs, 4 * np.arange(1, 19))  # every face of a box a quadrilateral
    assert np.array_equal(conn, np.concatenate([c.data.ravel() for c in m.cells]))
    for name, ncomp, where in (("displacement", 3, "PointData"), ("block_id", 1, "CellData"), ("moving", 1, "CellData"),
                               ("rotation", 3, "CellData"), ("centroid_displacement", 3, "CellData")):
        a = piece.find(f"{where}/DataArray[@Name='{name}']")
        assert a is not None and int(a.get("NumberOfComponents", 1)) == ncomp, name
        data = m.point_data[name] if where == "PointData" else cells_of(m, name)
        assert np.array_equal(_decode(a, header).reshape(data.shape), data), name
    assert np.all(cells_of(m, "block_id")[6:] == 1)  # both parts' faces belong to stone 1


def test_two_part_stone_moves_rigidly(tmp_path):
    """Every corner of both parts of a stone moves by the stone's rigid motion."""
    dx, angle = np.array([0.0, 0.2, 0.1]), -0.7
    v = fake_run(tmp_path / "run", dx, angle, cube_parts=True)
    m = meshio.read(samples(vtk.write(tmp_path / "run"))[1][1])
    expected = (v - [0, 0, 0.5]) @ rz(angle).T + [0, 0, 0.5] + dx
    assert m.point_data["displacement"][cube_rows(m)] == pytest.approx(expected - v, abs=tol.EXACT_ABS)
    block = cells_of(m, "block_id")
    assert cells_of(m, "centroid_displacement")[block == 1] == pytest.approx(np.tile(dx, (12, 1)), abs=tol.EXACT_ABS)


def test_tilt_in_the_world_frame(tmp_path):
    """A platform tilted by 10 deg towards +y (1 deg/s from t = 1 s to 11 s): in the world
    frame every block is turned by 10 deg about z x y = -x through the origin, so rotation
    (-10 deg, 0, 0) and displacement (Rx(-10 deg) - I) v; in the platform frame nothing moves."""
    tilt = {"type": "tilt", "start": 1.0, "end": 11.0, "params": {"rate_deg_s": 1.0, "towards": [0.0, 1.0, 0.0]}}
    v = fake_run(tmp_path / "run", [0.0, 0.0, 0.0], 0.0, times=(0.0, 11.0), stages=(GRAVITY, tilt))
    th = np.radians(10.0)
    rx = np.array([[1, 0, 0], [0, np.cos(th), np.sin(th)], [0, -np.sin(th), np.cos(th)]])  # about -x by th
    assert rx @ [0, 0, 1] == pytest.approx([0, np.sin(th), np.cos(th)])  # the top moves towards +y
    m = meshio.read(samples(vtk.write(tmp_path / "run"))[1][1])
    assert m.point_data["displacement"][cube_rows(m)] == pytest.approx(v @ rx.T - v, abs=tol.EXACT_ABS)
    assert cells_of(m, "rotation") == pytest.approx(np.tile([-th, 0, 0], (12, 1)), abs=tol.EXACT_ABS)
    c = np.array([0, 0, 0.5])
    assert cells_of(m, "centroid_displacement")[6:] == pytest.approx(np.tile(rx @ c - c, (6, 1)), abs=tol.EXACT_ABS)
    m = meshio.read(samples(vtk.write(tmp_path / "run", world=False, out=tmp_path / "pf"))[1][1])
    assert np.all(m.point_data["displacement"] == 0) and np.all(cells_of(m, "rotation") == 0)


def test_not_a_run_folder(tmp_path, capsys):
    (tmp_path / "x").mkdir()
    for f in ("spec.json", "geometry.json"):
        (tmp_path / "x" / f).write_text("{}")
    with pytest.raises(runfolder.NotARun, match="no summary.json"):
        vtk.write(tmp_path / "x")
    assert not (tmp_path / "x" / "vtk").exists()  # nothing written
    assert vtk.main([str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "no summary.json" in err and err.count("\n") == 1
    fake_run(tmp_path / "run", [0.1, 0, 0], 0.1)
    assert vtk.main([str(tmp_path / "run"), "--every", "0"]) == 2
    assert "--every" in capsys.readouterr().err
