"""Meshes of scanned stones (OBJ/PLY/STL) to blocks (drystone/geometry/meshes.py)."""
from pathlib import Path

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from drystone.geometry import blockfile as bf  # noqa: E402
from drystone.geometry import generators  # noqa: E402
from drystone.geometry import meshes  # noqa: E402
from drystone.geometry.blockfile import GeometryError  # noqa: E402
from drystone.mechanics import overlap  # noqa: E402
from drystone.model import case as case_mod  # noqa: E402

from tolerances import COACD_L_VOLUME_REL, EXACT_ABS, EXACT_REL  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCANS = ROOT / "data" / "examples" / "scans"
CASE = ROOT / "cases" / "examples" / "scanned_stones.toml"


def box(extents, at=(0.0, 0.0, 0.0), subdivide=0):
    m = trimesh.creation.box(extents=extents)
    for _ in range(subdivide):  # points in the faces' interiors and on edges: not corners
        m = m.subdivide()
    m.apply_translation(np.asarray(at, float) + np.asarray(extents, float) / 2.0)
    return m


def prism(poly, y0=0.0, y1=1.0):
    """A closed mesh: the polygon ``poly`` (x, z), star-shaped from its first corner,
    extruded along y."""
    n = len(poly)
    v = [[x, y0, z] for x, z in poly] + [[x, y1, z] for x, z in poly]
    f = [[0, i, i + 1] for i in range(1, n - 1)] + [[n, n + i + 1, n + i] for i in range(1, n - 1)]
    for i in range(n):
        j = (i + 1) % n
        f += [[j, i, n + i], [j, n + i, n + j]]
    m = trimesh.Trimesh(v, f, process=True)
    if m.volume < 0:
        m.invert()
    return m


def stone(d, bid):
    return next(b for b in d["blocks"] if b["id"] == bid)


def test_cube_and_box_give_the_exact_box(tmp_path):
    cube = tmp_path / "cube.stl"
    box([1.0, 1.0, 1.0], subdivide=2).export(cube)
    boxf = tmp_path / "box.obj"
    box([400.0, 300.0, 200.0], at=(1000.0, 0.0, 0.0), subdivide=1).export(boxf)
    for path, units, ext, lo in ((cube, "m", (1.0, 1.0, 1.0), (0, 0, 0)),
                                 (boxf, "mm", (0.4, 0.3, 0.2), (1.0, 0.0, 0.0))):
        d = meshes.make(files=[str(path)], units=units, fix_bottom=False)
        s = bf.parse(d)
        v = np.array(stone(d, 1)["vertices"])
        assert len(v) == 8
        assert np.allclose(np.sort(np.unique(v[:, 0])), [lo[0], lo[0] + ext[0]], atol=EXACT_ABS)
        assert np.allclose(v.min(axis=0), lo, atol=EXACT_ABS)
        assert np.allclose(v.max(axis=0), np.add(lo, ext), atol=EXACT_ABS)
        assert s.block(1).volume == pytest.approx(np.prod(ext), rel=EXACT_REL)
        assert "0.00 % of the hull's volume lost" in d["description"]
        # the platform slab under the stone, the stone's centroid a control point
        assert np.max(np.array(stone(d, 0)["vertices"])[:, 2]) == pytest.approx(lo[2], abs=EXACT_ABS)
        assert d["control_points"] == [{"name": "top_1", "block": 1,
                                        "position": pytest.approx(list(np.add(lo, np.divide(ext, 2))))}]


def test_mesh_with_a_hole_is_refused(tmp_path):
    m = box([1.0, 1.0, 1.0])
    holed = trimesh.Trimesh(m.vertices, m.faces[1:], process=False)
    path = tmp_path / "holed.ply"
    holed.export(path)
    with pytest.raises(GeometryError, match=r"holed\.ply: mesh is not closed") as e:
        meshes.make(files=[str(path)], units="m")
    assert "\n" not in str(e.value)


def test_unreadable_and_missing_files_are_refused(tmp_path):
    bad = tmp_path / "junk.obj"
    bad.write_text("this is not a mesh\n")
    with pytest.raises(GeometryError, match="junk.obj"):
        meshes.make(files=[str(bad)], units="m")
    with pytest.raises(GeometryError, match=r"nothere\.stl: mesh file not found"):
        meshes.make(files=[str(tmp_path / "nothere.stl")], units="m")
    with pytest.raises(GeometryError, match="exactly one of"):
        meshes.make(units="m")


def test_units_required_and_scaled(tmp_path):
    path = tmp_path / "s.stl"
    box([500.0, 300.0, 200.0]).export(path)
    with pytest.raises(GeometryError, match=r"s\.stl: mesh files carry no units"):
        meshes.make(files=[str(path)])
    with pytest.raises(GeometryError, match="'units'"):
        meshes.make(files=[str(path)], units="furlong")
    mm = bf.parse(meshes.make(files=[str(path)], units="mm", fix_bottom=False)).block(1).volume
    m = bf.parse(meshes.make(files=[str(path)], units="m", fix_bottom=False)).block(1).volume
    assert mm == pytest.approx(0.5 * 0.3 * 0.2, rel=EXACT_REL)
    assert m == pytest.approx(500.0 * 300.0 * 200.0, rel=EXACT_REL)


def test_up_axis(tmp_path):
    path = tmp_path / "yup.obj"
    box([0.4, 0.2, 0.3]).export(path)  # 0.2 m tall when y is up
    v = np.array(stone(meshes.make(files=[str(path)], units="m", up="y", fix_bottom=False), 1)["vertices"])
    assert np.ptp(v, axis=0) == pytest.approx([0.4, 0.3, 0.2], abs=EXACT_ABS)


def test_split_into_components(tmp_path):
    wall = trimesh.util.concatenate([box([0.4, 0.3, 0.2]), box([0.3, 0.3, 0.2], at=(0.05, 0.0, 0.2))])
    path = tmp_path / "wall.obj"  # text: binary STL stores float32 (0.05 to 7 digits)
    wall.export(path)
    d = meshes.make(file=str(path), units="m")
    assert [(b["id"], b["role"]) for b in d["blocks"]] == [(0, "platform"), (1, "fixed"), (2, "free")]
    s = bf.parse(d)
    assert s.block(1).volume == pytest.approx(0.024, rel=EXACT_REL)
    assert s.block(2).volume == pytest.approx(0.018, rel=EXACT_REL)
    assert [c["name"] for c in d["control_points"]] == ["top_2"]
    # one component with a hole among them: refused naming the file and component
    holed = trimesh.util.concatenate([box([0.4, 0.3, 0.2]),
                                      trimesh.Trimesh(*(lambda m: (m.vertices, m.faces[1:]))(
                                          box([0.3, 0.3, 0.2], at=(0.05, 0.0, 0.2))), process=False)])
    hp = tmp_path / "holed_wall.obj"
    holed.export(hp)
    with pytest.raises(GeometryError, match=r"holed_wall\.obj \(component 2 of 2\): mesh is not closed"):
        meshes.make(file=str(hp), units="m")


def test_ids_from_integer_stems_and_given_control_points(tmp_path):
    box([0.4, 0.3, 0.2]).export(tmp_path / "7.obj")
    box([0.3, 0.3, 0.2], at=(0.05, 0.0, 0.2)).export(tmp_path / "3.obj")
    d = meshes.make(folder=str(tmp_path), units="m", control_points=[["P", 0.2, 0.15, 0.45]])
    assert [(b["id"], b["role"]) for b in d["blocks"]] == [(0, "platform"), (3, "free"), (7, "fixed")]
    assert d["control_points"] == [{"name": "P", "block": 3, "position": [0.2, 0.15, 0.45]}]


def test_rounded_stone_hull_is_simplified_to_fit_the_kernel(tmp_path):
    path = tmp_path / "ball.obj"
    trimesh.creation.icosphere(subdivisions=3, radius=200.0).export(path)  # 642 hull corners
    d = meshes.make(files=[str(path)], units="mm", fix_bottom=False)
    v = np.array(stone(d, 1)["vertices"])
    assert len(v) <= meshes.MAX_CORNERS
    assert overlap.too_large(v) is None
    assert np.linalg.norm(v, axis=1) == pytest.approx(0.2, rel=1e-9)  # corners of the scan, inside its hull


coacd = pytest.importorskip("coacd")


def test_coacd_on_an_l(tmp_path):
    lshape = prism([(1, 1), (1, 2), (0, 2), (0, 0), (2, 0), (2, 1)])
    assert lshape.is_watertight and lshape.volume == pytest.approx(3.0)
    parts = meshes.decompose(lshape, threshold=0.05, seed=1)
    assert len(parts) >= 2
    total = sum(meshes.simplify(p)[2] for p in parts)
    assert total == pytest.approx(3.0, rel=COACD_L_VOLUME_REL)
    path = tmp_path / "L.stl"
    lshape.export(path)
    d = meshes.make(files=[str(path)], units="m", decomposition="coacd", seed=1, fix_bottom=False)
    assert d["version"] == bf.PARTS_VERSION and len(stone(d, 1)["parts"]) == len(parts)
    assert bf.parse(d).block(1).volume == pytest.approx(3.0, rel=COACD_L_VOLUME_REL)


def test_shipped_examples():
    d = meshes.make(folder=str(SCANS), units="mm")
    assert [(b["id"], b["role"]) for b in d["blocks"]] == [(0, "platform"), (1, "fixed"), (2, "free")]
    assert [c["name"] for c in d["control_points"]] == ["top_2"]
    for b in d["blocks"][1:]:
        assert overlap.too_large(b["vertices"]) is None
    for f in ("stone_1.obj", "stone_2.ply"):
        assert (SCANS / f).stat().st_size < 200_000
        assert meshes.load(SCANS / f).is_watertight
    c = case_mod.load(CASE)
    g = c["case"]["geometry"]
    assert g["generator"] == "meshes" and Path(g["folder"]) == SCANS.resolve()
    assert bf.parse(generators.generate(g)).ids("free") == [2]


def test_case_paths_resolve_relative_to_the_case_file(tmp_path):
    """folder, file and files of a generator are read beside the case file, whatever the
    working folder; a missing one is refused naming it."""
    (tmp_path / "scans").mkdir()
    (tmp_path / "scans" / "a.obj").write_text("")
    geo = {"generator": "meshes", "files": ["scans/a.obj"], "units": "m"}
    out = case_mod._generator_paths(geo, tmp_path, "c.toml")
    assert out["files"] == [str((tmp_path / "scans" / "a.obj").resolve())] and geo["files"] == ["scans/a.obj"]
    with pytest.raises(case_mod.CaseError, match=r"'files': .*b\.obj not found"):
        case_mod._generator_paths(dict(geo, files=["scans/a.obj", "scans/b.obj"]), tmp_path, "c.toml")
    with pytest.raises(case_mod.CaseError, match="'folder': .* is not a folder"):
        case_mod._generator_paths({"generator": "outlines", "folder": "nowhere"}, tmp_path, "c.toml")


# --- bad meshes named: non-finite vertices, no volume, several bodies, odd file names --------

def test_non_finite_vertex_is_named_not_called_a_hole(tmp_path):
    """A NaN vertex was dropped by trimesh's processing and the mesh then reported 'not
    closed'; it is now named before processing."""
    m = box([1.0, 1.0, 1.0])
    v = np.array(m.vertices)
    v[3, 1] = np.nan
    path = tmp_path / "nan.obj"
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in v) + "".join(f"f {a + 1} {b + 1} {c + 1}\n"
                                                                           for a, b, c in m.faces))
    with pytest.raises(GeometryError, match=r"nan\.obj: mesh has 1 vertex\(es\) with non-finite coordinates .*"
                                            r"the first vertex 3 at \([^)]*nan[^)]*\)"):
        meshes.make(files=[str(path)], units="m")


def test_closed_mesh_of_no_volume_is_refused(tmp_path):
    """Four coplanar points joined as a tetrahedron: closed (every edge in two faces) but flat;
    was a QhullError traceback."""
    flat = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]],
                           process=False)
    with np.errstate(invalid="ignore"):  # trimesh divides by the zero volume for the centre of mass
        assert flat.is_watertight and flat.volume == 0.0
    flat.export(tmp_path / "flat.stl")
    with pytest.raises(GeometryError, match=r"flat\.stl: mesh encloses no volume"):
        meshes.make(files=[str(tmp_path / "flat.stl")], units="m")


@pytest.mark.parametrize("mode", ["folder", "files", "file"])
def test_a_file_of_two_bodies_is_not_one_stone(tmp_path, mode):
    """Two separate boxes in one file became one convex stone bridging the gap (its hull 175 %
    above the mesh); in folder or files mode (one stone per file), or file mode with split =
    false, it is refused naming the file; file mode with split = true still splits it."""
    (tmp_path / "w").mkdir()
    (box([1.0, 1.0, 1.0]) + box([1.0, 1.0, 1.0], at=(3.0, 0.0, 0.0))).export(tmp_path / "w" / "1.stl")
    box([1.0, 1.0, 1.0], at=(0.0, 0.0, 1.0)).export(tmp_path / "w" / "2.stl")
    kw = {"folder": {"folder": str(tmp_path / "w")}, "files": {"files": [str(tmp_path / "w" / "1.stl")]},
          "file": {"file": str(tmp_path / "w" / "1.stl"), "split": False}}[mode]
    with pytest.raises(GeometryError, match=r"w/1\.stl: the mesh holds 2 separate bodies, not one stone"):
        meshes.make(units="m", **kw)
    d = meshes.make(file=str(tmp_path / "w" / "1.stl"), units="m", fix_bottom=False)
    assert [b["id"] for b in d["blocks"]] == [0, 1, 2]


def test_file_names_that_are_not_plain_ids(tmp_path):
    """'².stl' (a superscript digit: str.isdigit but not int) and a 40-digit stem were a
    traceback and an id no run could store; such names are numbered in order, as any
    non-integer stem."""
    box([1.0, 1.0, 1.0]).export(tmp_path / "².stl")
    box([1.0, 1.0, 1.0], at=(2.0, 0.0, 0.0)).export(tmp_path / ("7" * 40 + ".stl"))
    d = meshes.make(folder=str(tmp_path), units="m", fix_bottom=False)
    assert [b["id"] for b in d["blocks"]] == [0, 1, 2]
