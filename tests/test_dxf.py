"""CAD drawings (DXF) of a wall's face extruded to blocks (drystone/geometry/dxf.py)."""
from pathlib import Path

import numpy as np
import pytest

ezdxf = pytest.importorskip("ezdxf")

from drystone.geometry import blockfile as bf  # noqa: E402
from drystone.geometry import dxf  # noqa: E402
from drystone.geometry import generators  # noqa: E402
from drystone.geometry import outlines as ol  # noqa: E402
from drystone.geometry.blockfile import GeometryError  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "data" / "examples" / "polygonal_wall.dxf"

# a 2 x 1.2 m polygonal wall of 9 convex stones in three courses (mm; x along the wall, z up);
# the shipped example data/examples/polygonal_wall.dxf is write_dxf(WALL, ..., PLATFORM, CPS)
WALL = {
    1: [(0, 0), (620, 0), (700, 420), (0, 480)],
    2: [(620, 0), (1380, 0), (1300, 500), (700, 420)],
    3: [(1380, 0), (2000, 0), (2000, 450), (1300, 500)],
    4: [(0, 480), (350, 450), (450, 900), (0, 870)],
    5: [(350, 450), (700, 420), (1300, 500), (1250, 950), (450, 900)],
    6: [(1300, 500), (2000, 450), (2000, 880), (1250, 950)],
    7: [(0, 870), (450, 900), (500, 1200), (0, 1200)],
    8: [(450, 900), (1250, 950), (1200, 1200), (500, 1200)],
    9: [(1250, 950), (2000, 880), (2000, 1200), (1200, 1200)],
}
PLATFORM = [(-500, -100), (2500, -100), (2500, 0), (-500, 0)]
CPS = [("A", 850, 1200), ("B", 1600, 1200)]
L_STONE = [(0, 0), (1000, 0), (1000, 300), (400, 300), (400, 700), (0, 700)]


def write_dxf(path, stones, insunits=4, scale=1.0, layer="stones", platform=None, control_points=(),
              label=True, layers=None, close_by_point=False):
    """A DXF drawing of ``stones`` ({id: [(x, z), ...]} in drawing units x ``scale``): one
    closed LWPOLYLINE per stone, a TEXT id at its centroid."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = insunits
    msp = doc.modelspace()
    for bid, pts in stones.items():
        pts = [(x * scale, z * scale) for x, z in pts]
        lay = (layers or {}).get(bid, layer)
        if close_by_point:
            msp.add_lwpolyline(pts + [pts[0]], dxfattribs={"layer": lay})
        else:
            msp.add_lwpolyline(pts, close=True, dxfattribs={"layer": lay})
        if label:
            c = ol.centroid(np.array(pts, float))
            msp.add_text(str(bid), dxfattribs={"layer": "labels", "height": 50 * scale}).set_placement(tuple(c))
    if platform:
        msp.add_lwpolyline([(x * scale, z * scale) for x, z in platform], close=True,
                           dxfattribs={"layer": "platform"})
    for name, x, z in control_points:
        msp.add_text(name, dxfattribs={"layer": "control_points", "height": 50 * scale}).set_placement(
            (x * scale, z * scale))
    msp.add_line((0, -200 * scale), (2000 * scale, -200 * scale), dxfattribs={"layer": "dimensions"})
    doc.saveas(path)
    return path


def write_folder(folder, stones, scale):
    folder.mkdir()
    for bid, pts in stones.items():
        (folder / f"{bid}.csv").write_text("\n".join(f"{x * scale!r} {z * scale!r}" for x, z in pts) + "\n")
    return folder


def _core(d):
    """A block file without its provenance (name, generator, description)."""
    return {k: v for k, v in d.items() if k not in ("name", "generator", "description")}


def test_dxf_and_outline_folder_give_the_same_block_file(tmp_path):
    f = write_dxf(tmp_path / "w.dxf", WALL, insunits=6, scale=0.001)
    a = dxf.make(f, thickness=0.5)
    b = ol.make(write_folder(tmp_path / "w", WALL, 0.001), thickness=0.5)
    assert _core(a) == _core(b)
    bs = bf.parse(a)
    assert bs.ids("fixed") == [1, 2, 3] and bs.ids("free") == [4, 5, 6, 7, 8, 9]
    assert "dimensions" in a["description"]  # the ignored layer is noted


def test_units_mm_drawing_is_the_m_drawing_scaled(tmp_path):
    mm = dxf.make(write_dxf(tmp_path / "mm.dxf", WALL, insunits=4), thickness=0.5)
    m = dxf.make(write_dxf(tmp_path / "m.dxf", WALL, insunits=6, scale=0.001), thickness=0.5)
    assert mm["generator"]["units"] == "mm" and m["generator"]["units"] == "m"
    for x, y in zip(mm["blocks"], m["blocks"]):
        assert x["id"] == y["id"] and x["role"] == y["role"]
        np.testing.assert_allclose(x["vertices"], y["vertices"], atol=1e-12)
    assert bf.parse(mm).block(5).volume == pytest.approx(bf.parse(m).block(5).volume, rel=1e-12)


def test_unitless_refused_unless_units_given(tmp_path):
    f = write_dxf(tmp_path / "u.dxf", WALL, insunits=0)
    with pytest.raises(GeometryError, match=r"u\.dxf: the drawing has no units .*units ="):
        dxf.make(f, thickness=0.5)
    d = dxf.make(f, thickness=0.5, units="mm")
    assert bf.parse(d).block(1).vertices[:, 0].max() == pytest.approx(0.7)
    with pytest.raises(GeometryError, match="contradicts"):
        dxf.make(write_dxf(tmp_path / "m.dxf", WALL, insunits=6), thickness=0.5, units="mm")


def test_unlabelled_stone_refused_naming_handle_and_layer(tmp_path):
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (1, 0), (1, 1), (0, 1)], close=True, dxfattribs={"layer": "Free"})
    h = msp.add_lwpolyline([(0, 1), (1, 1), (1, 2), (0, 2)], close=True, dxfattribs={"layer": "Free"}).dxf.handle
    msp.add_text("1").set_placement((0.5, 0.5))
    doc.saveas(tmp_path / "x.dxf")
    with pytest.raises(GeometryError, match=rf"x\.dxf: polyline handle {h} on layer 'Free' has no id label"):
        dxf.make(tmp_path / "x.dxf", thickness=0.5)


@pytest.mark.parametrize("kind", ["duplicate", "open", "none", "unreadable", "arc"])
def test_bad_drawings_name_the_file(tmp_path, kind):
    f = tmp_path / "bad.dxf"
    if kind == "duplicate":
        doc = ezdxf.new("R2010")
        msp = doc.modelspace()
        for z in (0, 1):
            msp.add_lwpolyline([(0, z), (1, z), (1, z + 1), (0, z + 1)], close=True, dxfattribs={"layer": "stones"})
            msp.add_text("3").set_placement((0.5, z + 0.5))
        doc.saveas(f)
        match = r"bad\.dxf: stone 3 drawn twice"
    elif kind == "open":
        doc = ezdxf.new("R2010")
        doc.modelspace().add_lwpolyline([(0, 0), (1, 0), (1, 1)], dxfattribs={"layer": "stones"})
        doc.saveas(f)
        match = r"bad\.dxf: LWPOLYLINE handle \w+ on layer 'stones' is not closed"
    elif kind == "none":
        write_dxf(f, WALL, layer="walls")
        match = r"bad\.dxf: no closed polylines on the stone layers"
    elif kind == "arc":
        doc = ezdxf.new("R2010")
        doc.modelspace().add_lwpolyline([(0, 0, 0, 0, 0.5), (1, 0), (1, 1)], close=True, dxfattribs={"layer": "stones"})
        doc.saveas(f)
        match = r"bad\.dxf: LWPOLYLINE handle \w+ on layer 'stones' has arcs"
    else:
        f.write_text("this is not a drawing\n")
        match = r"bad\.dxf: not a readable DXF file"
    with pytest.raises(GeometryError, match=match):
        dxf.make(f, thickness=0.5)


def test_non_convex_stone_becomes_parts_and_roles_from_layers(tmp_path):
    stones = {1: L_STONE, 2: [(400, 300), (1000, 300), (1000, 700), (400, 700)],
              3: [(0, 700), (1000, 700), (1000, 900), (0, 900)]}
    f = write_dxf(tmp_path / "l.dxf", stones, layers={1: "FREE", 3: "fixed"}, close_by_point=True)
    d = dxf.make(f, thickness=0.4)
    assert d["version"] == bf.PARTS_VERSION
    b1, b2, b3 = d["blocks"][1:]
    assert "parts" in b1 and len(b1["parts"]) == 2 and "vertices" in b2
    assert (b1["role"], b2["role"], b3["role"]) == ("free", "free", "fixed")  # layers override fix_bottom
    bs = bf.parse(d)
    assert bs.block(1).volume == pytest.approx((0.3 + 0.4 * 0.4) * 0.4)
    # the same L as an outline file gives the same parts
    o = ol.make(write_folder(tmp_path / "o", stones, 0.001), thickness=0.4)
    assert o["blocks"][1]["parts"] == b1["parts"]


def test_default_control_points_on_the_top_stones(tmp_path):
    d = dxf.make(write_dxf(tmp_path / "w.dxf", WALL), thickness=0.5)
    cps = {c["name"]: c for c in d["control_points"]}
    assert sorted(cps) == ["top_7", "top_8", "top_9"]
    for bid in (7, 8, 9):
        c = cps[f"top_{bid}"]
        want = ol.centroid(np.array(WALL[bid], float) / 1000)
        assert c["block"] == bid and c["position"] == pytest.approx([want[0], -0.25, want[1]])


def test_given_control_points_platform_and_depth(tmp_path):
    f = write_dxf(tmp_path / "w.dxf", WALL, platform=PLATFORM, control_points=CPS)
    doc = ezdxf.readfile(f)
    doc.modelspace().add_text("depth=0.3", dxfattribs={"layer": "labels"}).set_placement((1000, 1100))
    doc.saveas(f)
    d = dxf.make(f, thickness=0.5)
    assert [(c["name"], c["block"]) for c in d["control_points"]] == [("A", 8), ("B", 9)]
    assert d["control_points"][0]["position"] == pytest.approx([0.85, -0.15, 1.2])
    bs = bf.parse(d)
    assert bs.block(0).vertices[:, 0].min() == pytest.approx(-0.5)
    assert bs.block(8).vertices[:, 1].max() == pytest.approx(0.15) and bs.block(7).vertices[:, 1].max() == 0.25


def test_polyline_insert_attributes_mtext_and_points(tmp_path):
    """A 2D POLYLINE labelled by a block reference's ID and DEPTH attributes, an LWPOLYLINE by
    an MTEXT 'id=5'; a POINT on control_points is P1."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_polyline2d([(0, 0), (1, 0), (1, 1), (0, 1)], close=True, dxfattribs={"layer": "stones"})
    blk = doc.blocks.new("STONEID")
    blk.add_attdef("ID", (0, 0))
    blk.add_attdef("DEPTH", (0, 0.1))
    msp.add_blockref("STONEID", (0.5, 0.5)).add_auto_attribs({"ID": "4", "DEPTH": "0.3"})
    msp.add_lwpolyline([(0, 1), (1, 1), (1, 2), (0, 2)], close=True, dxfattribs={"layer": "stones"})
    msp.add_mtext("id=5", dxfattribs={"insert": (0.5, 1.5)})
    msp.add_point((0.5, 2.0), dxfattribs={"layer": "control_points"})
    doc.saveas(tmp_path / "t.dxf")
    d = dxf.make(tmp_path / "t.dxf", thickness=0.5)
    assert [(b["id"], b["role"]) for b in d["blocks"]] == [(0, "platform"), (4, "fixed"), (5, "free")]
    assert d["control_points"] == [{"name": "P1", "block": 5, "position": [0.5, -0.25, 2.0]}]
    assert bf.parse(d).block(4).vertices[:, 1].max() == pytest.approx(0.15)


def test_generator_registry_and_shipped_example():
    d = generators.generate({"generator": "dxf", "file": str(EXAMPLE), "thickness": 0.5})
    bs = bf.parse(d)
    assert bs.ids("free") == [4, 5, 6, 7, 8, 9] and bs.ids("fixed") == [1, 2, 3]
    assert [c["name"] for c in d["control_points"]] == ["A", "B"]
    assert d["version"] == bf.VERSION  # convex stones only: the example runs


def test_case_resolves_the_file_relative_to_the_case(tmp_path):
    from drystone.model import case as cs
    raw = {"case": {"geometry": {"generator": "dxf", "file": "wall.dxf", "thickness": 0.5}},
           "stages": [{"type": "gravity", "duration": 0.1}]}
    with pytest.raises(cs.CaseError, match=r"geometry 'file': .*wall\.dxf not found"):
        cs.validate(raw, "c.toml", tmp_path)
    write_dxf(tmp_path / "wall.dxf", WALL)
    c = cs.validate(raw, "c.toml", tmp_path)
    assert c["case"]["geometry"]["file"] == str((tmp_path / "wall.dxf").resolve())
