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
from tolerances import EXACT_ABS, EXACT_REL  # noqa: E402

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


# --- every entity on a role layer read or refused; block references; OCS; labels ---------

def _doc(insunits=6):
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = insunits
    return doc, doc.modelspace()


def _stone(msp, x, z, bid=None, w=0.45, h=0.3, layer="stones", **attribs):
    """A w x h stone (drawing units) at (x, z), labelled ``bid`` at its middle."""
    e = msp.add_lwpolyline([(x, z), (x + w, z), (x + w, z + h), (x, z + h)], close=True,
                           dxfattribs={"layer": layer, **attribs})
    if bid is not None:
        msp.add_text(str(bid), dxfattribs={"layer": "labels"}).set_placement((x + w / 2, z + h / 2))
    return e


def _corners(d, bid):
    """(x, z) bounding box of stone ``bid`` of a block-file dict: ((xmin, zmin), (xmax, zmax))."""
    v = np.array(next(b for b in d["blocks"] if b["id"] == bid)["vertices"])[:, [0, 2]]
    return v.min(axis=0), v.max(axis=0)


@pytest.mark.parametrize("kind, layer", [("SPLINE", "stones"), ("CIRCLE", "stones"), ("POINT", "free"),
                                         ("LINE", "platform"), ("CIRCLE", "control_points"),
                                         ("SPLINE", "in_block")])
def test_every_entity_on_a_role_layer_is_read_or_refused(tmp_path, kind, layer):
    """A SPLINE, CIRCLE, LINE or POINT on a stone, platform or control-point layer was dropped
    (the run had 4 of 5 stones): refused naming its handle (or block) and type."""
    doc, msp = _doc()
    for k in range(4):
        _stone(msp, 0.45 * k, 0.0, k + 1)
    target = msp
    if layer == "in_block":  # inside a block reference on the stones layer (layer 0 takes the INSERT's)
        target = doc.blocks.new("ODD")
        msp.add_blockref("ODD", (0.0, 0.3), dxfattribs={"layer": "stones"})
        layer = "0"
    attribs = {"layer": layer}
    e = {"SPLINE": lambda: target.add_spline([(0, 0.5), (0.2, 0.7), (0.45, 0.5)], dxfattribs=attribs),
         "CIRCLE": lambda: target.add_circle((0.2, 0.5), 0.1, dxfattribs=attribs),
         "POINT": lambda: target.add_point((0.2, 0.5), dxfattribs=attribs),
         "LINE": lambda: target.add_line((-1, 0), (3, 0), dxfattribs=attribs)}[kind]()
    doc.saveas(tmp_path / "e.dxf")
    what = rf"{kind} in block 'ODD' \(INSERT handle \w+\) on layer 'stones'" if layer == "0" else (
        rf"{kind} handle {e.dxf.handle} on layer '{layer}'")
    with pytest.raises(GeometryError, match=rf"e\.dxf: {what} cannot be read: that layer takes .*not a {kind}"):
        dxf.make(tmp_path / "e.dxf", thickness=0.5)


def test_stones_in_block_references_are_exploded_with_their_transform(tmp_path):
    """A stone drawn inside a block (its own id text with it), placed twice by INSERTs (one
    rotated 90 degrees and scaled 2 x), and one in a block nested in another: each lands where
    the reference puts it, as if drawn there (was: dropped, 'no block has role free')."""
    doc, msp = _doc()
    _stone(msp, 0.0, 0.0, 1, w=2.0)
    blk = doc.blocks.new("STONE")  # a 0.3 x 0.2 stone at the block's origin, on layer 0
    blk.add_lwpolyline([(0, 0), (0.3, 0), (0.3, 0.2), (0, 0.2)], close=True)
    ids = doc.blocks.new("STONE_ID")  # the same stone with its id as an attribute
    ids.add_lwpolyline([(0, 0), (0.3, 0), (0.3, 0.2), (0, 0.2)], close=True, dxfattribs={"layer": "free"})
    ids.add_attdef("ID", (0.1, 0.1))
    msp.add_blockref("STONE", (0.1, 0.3), dxfattribs={"layer": "stones"})
    msp.add_text("2", dxfattribs={"layer": "labels"}).set_placement((0.25, 0.4))
    # rotated by 90 degrees about its insertion point and scaled 2 x: x 0.8-1.2, z 0.3-0.9
    msp.add_blockref("STONE", (1.2, 0.3), dxfattribs={"layer": "stones", "rotation": 90, "xscale": 2, "yscale": 2})
    msp.add_text("3", dxfattribs={"layer": "labels"}).set_placement((1.0, 0.6))
    msp.add_blockref("STONE_ID", (1.5, 0.3)).add_auto_attribs({"ID": "4"})
    outer = doc.blocks.new("OUTER")
    outer.add_blockref("STONE", (0.0, 0.0))
    outer.add_text("5").set_placement((0.1, 0.1))
    msp.add_blockref("OUTER", (0.1, 0.6), dxfattribs={"layer": "stones"})
    doc.saveas(tmp_path / "b.dxf")
    d = dxf.make(tmp_path / "b.dxf", thickness=0.5)
    assert [b["id"] for b in d["blocks"]] == [0, 1, 2, 3, 4, 5]
    want = {2: ((0.1, 0.3), (0.4, 0.5)), 3: ((0.8, 0.3), (1.2, 0.9)), 4: ((1.5, 0.3), (1.8, 0.5)),
            5: ((0.1, 0.6), (0.4, 0.8))}
    for bid, (lo, hi) in want.items():
        got = _corners(d, bid)
        np.testing.assert_allclose(got[0], lo, atol=EXACT_ABS)
        np.testing.assert_allclose(got[1], hi, atol=EXACT_ABS)
    assert bf.parse(d).block(3).volume == pytest.approx(0.4 * 0.6 * 0.5, rel=EXACT_REL)
    assert {b["id"]: b["role"] for b in d["blocks"]}[4] == "free"  # its layer in the block
    assert "ignored layers" not in d["description"]


def test_stone_and_label_mirrored_in_cad_land_where_drawn(tmp_path):
    """A stone mirrored in CAD has extrusion (0, 0, -1): its points are in an object
    coordinate system whose x is the world's -x. It was placed at -0.45..0 m, in mid-air beside
    the wall; read in world coordinates it is the drawn 0..0.45 m (its label too)."""
    doc, msp = _doc()
    _stone(msp, 0.0, 0.0, 1)
    _stone(msp, -0.45, 0.3, extrusion=(0, 0, -1))  # world x 0..0.45
    msp.add_text("2", dxfattribs={"layer": "labels", "extrusion": (0, 0, -1)}).set_placement((-0.2, 0.45))
    msp.add_text("A", dxfattribs={"layer": "control_points", "extrusion": (0, 0, -1)}).set_placement((-0.1, 0.6))
    doc.saveas(tmp_path / "m.dxf")
    d = dxf.make(tmp_path / "m.dxf", thickness=0.5)
    lo, hi = _corners(d, 2)
    np.testing.assert_allclose([lo, hi], [(0.0, 0.3), (0.45, 0.6)], atol=EXACT_ABS)
    assert d["control_points"] == [{"name": "A", "block": 2, "position": pytest.approx([0.1, -0.25, 0.6])}]
    assert bf.parse(d).block(2).volume == pytest.approx(0.45 * 0.3 * 0.5, rel=EXACT_REL)
    # a stone drawn in another plane (extrusion along x) is refused, not flattened
    doc, msp = _doc()
    _stone(msp, 0.0, 0.0, 1)
    e = _stone(msp, 0.0, 0.3, 2, extrusion=(1, 0, 0))
    doc.saveas(tmp_path / "x.dxf")
    with pytest.raises(GeometryError, match=rf"LWPOLYLINE handle {e.dxf.handle} on layer 'stones' is not drawn in "
                                            r"the XY plane"):
        dxf.make(tmp_path / "x.dxf", thickness=0.5)


@pytest.mark.parametrize("label, match", [
    ("depth=0,3", r"stone 2 \(polyline handle \w+\): cannot read the depth label 'depth=0,3' \(TEXT handle \w+\)"),
    ("depth=0.3m", r"stone 2 .*cannot read the depth label 'depth=0\.3m'"),
    ("depth: 0.3", r"stone 2 .*cannot read the depth label 'depth: 0\.3'"),
    ("DEPTH 0.3", r"stone 2 .*cannot read the depth label 'DEPTH 0\.3'"),
    ("depth=-0.3", r"stone 2: depth must be a number > 0 \(m\), got 'depth=-0\.3'"),
    ("id: 3", r"polyline handle \w+ on layer 'stones': cannot read the id label 'id: 3'"),
    ("1" * 40, r"polyline handle \w+ on layer 'stones': id label '1{40}' \(TEXT handle \w+\) is not an id: "
               r"ids are integers 1 to 2147483647"),
    ("0", r"polyline handle \w+ on layer 'stones': id label '0' .*is not an id.*\(0 is the platform's\)"),
])
def test_unreadable_labels_are_refused_naming_the_stone(tmp_path, label, match):
    """A depth label that does not read (decimal comma, a unit, a colon) was ignored and the
    default depth used; a 40-digit id was accepted and broke the run's outputs at the end."""
    doc, msp = _doc()
    _stone(msp, 0.0, 0.0, 1)
    _stone(msp, 0.0, 0.3, None if label[0] in "10" else 2)
    msp.add_text(label, dxfattribs={"layer": "labels"}).set_placement((0.1, 0.4))
    doc.saveas(tmp_path / "l.dxf")
    with pytest.raises(GeometryError, match=rf"l\.dxf: {match}") as err:
        dxf.make(tmp_path / "l.dxf", thickness=0.5)
    assert "\n" not in str(err.value)


def test_fixed_stones_stand_on_the_drawn_platform(tmp_path):
    """A platform drawn 1 m below the stones: the bottom course was fixed in mid-air. Now a
    drawn platform no stone stands on is refused, and so is a stone on layer 'fixed' that
    stands neither on the platform nor on fixed stones that do (within standing_tol); one on
    the fixed bottom course is accepted, and so is a course within the tolerance."""
    def drawing(name, platform_z, extra=None):
        doc, msp = _doc()
        _stone(msp, 0.0, 0.0, 1)
        _stone(msp, 0.45, 0.0, 2)
        _stone(msp, 0.2, 0.3, 3)
        if extra:
            _stone(msp, *extra[0], extra[1], layer="fixed")
        msp.add_lwpolyline([(-1, platform_z - 0.1), (2, platform_z - 0.1), (2, platform_z), (-1, platform_z)],
                           close=True, dxfattribs={"layer": "platform"})
        doc.saveas(tmp_path / name)
        return tmp_path / name

    with pytest.raises(GeometryError, match=r"below\.dxf \(stone 1, polyline handle \w+, layer 'stones'\): no stone "
                                            r"stands on the drawn platform; the lowest, this one, is 1 m from it "
                                            r"\(tolerance 0\.0009 m: 0\.1 % of the 0\.9 m wall\)"):
        dxf.make(drawing("below.dxf", -1.0), thickness=0.5)
    with pytest.raises(GeometryError, match=r"hover\.dxf \(stone 4, .*layer 'fixed'\): a fixed stone must stand on "
                                            r"the platform .* it is 0\.5 m from the platform"):
        dxf.make(drawing("hover.dxf", 0.0, ((1.5, 0.5), 4)), thickness=0.5)
    d = dxf.make(drawing("chain.dxf", 0.0, ((0.9, 0.0), 4)), thickness=0.5)  # on the platform
    assert {b["id"]: b["role"] for b in d["blocks"]} == {0: "platform", 1: "fixed", 2: "fixed", 3: "free", 4: "fixed"}
    d = dxf.make(drawing("near.dxf", -0.5 * bf.STANDING_TOL), thickness=0.5, fix_bottom=True)
    assert bf.parse(d).ids("fixed") == [1, 2]
    # a fixed stone on fixed stones that stand on the platform: a chain, accepted
    doc, msp = _doc()
    _stone(msp, 0.0, 0.0, 1)
    _stone(msp, 0.0, 0.3, 2, layer="fixed")
    _stone(msp, 0.0, 0.6, 3)
    msp.add_lwpolyline([(-1, -0.1), (2, -0.1), (2, 0), (-1, 0)], close=True, dxfattribs={"layer": "platform"})
    doc.saveas(tmp_path / "c.dxf")
    assert bf.parse(dxf.make(tmp_path / "c.dxf", thickness=0.5)).ids("fixed") == [1, 2]


def _grid_wall(n, cols=20):
    """n stones in running bond, 0.4 x 0.25 m, ids 1..n, one label each at an off-centre
    point (so that a label lies near, not at, the middle of its stone)."""
    stones = {}
    for k in range(n):
        r, c = divmod(k, cols)
        x0, z0 = c * 0.4 + (0.2 if r % 2 else 0.0), r * 0.25
        stones[k + 1] = [(x0, z0), (x0 + 0.4, z0), (x0 + 0.4, z0 + 0.25), (x0, z0 + 0.25)]
    return stones


def test_labels_found_by_the_sorted_index_are_those_inside(tmp_path):
    """The labels are matched to stones through a sort on x and each stone's bounding box
    (``outlines.points_in``) instead of each label against each stone (1000 stones took 196 s,
    now about 8 s: docs/reliability.md). Same answer as the plain test on random points,
    points on edges and corners included, and a 300-stone drawing gets every id right."""
    rng = np.random.default_rng(3)
    polys = [np.array(p, float) for p in _grid_wall(60, cols=10).values()]
    pts = np.vstack([rng.uniform([-0.5, -0.5], [4.7, 2.2], (400, 2)),
                     np.array([p[0] for p in polys]), np.array([(p[0] + p[1]) / 2 for p in polys])])
    got = ol.points_in(polys, pts)
    for poly, idx in zip(polys, got):
        want = [i for i, q in enumerate(pts) if ol._distance(poly, q) == 0.0]
        assert idx.tolist() == want
    stones = _grid_wall(300)
    d = dxf.make(write_dxf(tmp_path / "w.dxf", stones, insunits=6), thickness=0.3)
    bs = bf.parse(d)
    assert bs.ids() == list(range(301))
    for bid in (1, 150, 300):
        np.testing.assert_allclose(bs.block(bid).centroid[[0, 2]], ol.centroid(np.array(stones[bid], float)),
                                   atol=EXACT_ABS)
