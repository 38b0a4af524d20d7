"""Issue 12 (reliability), geometry: every bad block file or generator parameter gives a
GeometryError naming the file or generator, the block / joint / control point or the
parameter, never a numpy/scipy traceback or a silent acceptance; the overlap test is a
sort and sweep (2000 blocks in well under a second)."""
import json
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.geometry import generators
from drystone.geometry import outlines as ol
from drystone.geometry import polyhedron as ph

ROOT = Path(__file__).resolve().parents[1]
L_OUTLINE = [(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)]  # (x, z) m, re-entrant corner (1, 1)


def extruded(outline, depth=0.5):
    """Vertices of a 2D outline (x, z) extruded through y in [-depth/2, depth/2]."""
    return [[x, y, z] for x, z in outline for y in (-depth / 2, depth / 2)]


def blocks_file(vertices, **over):
    """A platform (id 0) and one free block (id 1) of the given vertices on it, a joint and
    a control point."""
    d = {"format": bf.FORMAT, "version": 1, "name": "t",
         "materials": {"stone": {"density": 2300, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}},
         "blocks": [{"id": 0, "role": "platform", "material": "stone",
                     "vertices": bf.box_vertices((0, 0, -0.05), (5, 5, 0.1))},
                    {"id": 1, "role": "free", "material": "stone", "vertices": vertices}],
         "joints": [{"blocks": [1, 0], "mu": 0.5}],
         "control_points": [{"name": "top", "block": 1, "position": [0.0, 0.0, 0.2]}]}
    d.update(over)
    return d


def load_error(tmp_path, data) -> str:
    """The GeometryError message of loading ``data`` written as a JSON file (checked to
    name the file)."""
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(data))
    with pytest.raises(bf.GeometryError) as err:
        bf.load(p)
    assert str(p) in str(err.value)
    return str(err.value)


# --- 1. non-convex blocks ---------------------------------------------------------------

def test_l_shaped_block_is_refused_not_replaced_by_its_hull(tmp_path):
    """An extruded L (12 vertices): its re-entrant corners lie on the hull's front and back
    faces, so 'no vertex inside the hull' let it through, and YADE built the hull (+17 %)."""
    v = extruded(L_OUTLINE)
    assert ph.volume_centroid(v)[0] == pytest.approx(3.5 * 0.5)  # the hull; the L is 3 x 0.5
    msg = load_error(tmp_path, blocks_file(v))
    assert "block 1: not convex: vertex 6 at (1, -0.25, 1) m, vertex 7 at (1, 0.25, 1) m are not corners" in msg
    p = tmp_path / "bad.json"
    cli = subprocess.run([sys.executable, "-m", "drystone.geometry", "validate", str(p)], capture_output=True, text=True,
                         cwd=ROOT)
    assert cli.returncode == 1 and "not convex" in cli.stderr and "Traceback" not in cli.stderr


BOX = bf.box_vertices((0, 0, 0.5), (1, 1, 1))


@pytest.mark.parametrize("extra, message", [
    ([0.5, 0.0, 0.5], "not convex: vertex 8 at (0.5, 0, 0.5)"),  # in a face (x = 0.5)
    ([0.5, 0.5, 0.3], "not convex: vertex 8 at (0.5, 0.5, 0.3)"),  # on an edge
    ([0.1, 0.1, 0.5], "not convex: vertex 8 at (0.1, 0.1, 0.5)"),  # inside
    ([0.5, 0.5 + 1e-13, 0.3], "not convex: vertex 8"),  # on an edge but for round-off
    ([0.5, 0.5, 1.0], "vertices 7 and 8 coincide at (0.5, 0.5, 1)"),  # a repeated corner
])
def test_vertices_that_are_not_corners_are_refused(tmp_path, extra, message):
    assert message in load_error(tmp_path, blocks_file(BOX + [extra]))


def test_real_corners_close_to_flat_are_kept():
    """A roof 0.1 mm high over a 1 m box is a corner (9 vertices), so is a corner pulled out
    by 1 um: both blocks are accepted with every vertex as given, and their volumes count
    the roof (a pyramid, 1 m^2 x 1e-4 m / 3) and the pulled edge (two slivers of 1 m^2 x
    0.5 um / 2)."""
    roof = BOX + [[0.0, 0.0, 1.0 + 1e-4]]
    b = bf.parse(blocks_file(roof)).block(1)
    assert np.array_equal(b.vertices, roof) and b.volume == pytest.approx(1.0 + 1e-4 / 3, rel=tol.EXACT_REL)
    pulled = [[x * (1 + 1e-6), y * (1 + 1e-6), z] if (x, y) == (0.5, 0.5) else [x, y, z] for x, y, z in BOX]
    b = bf.parse(blocks_file(pulled)).block(1)
    assert np.array_equal(b.vertices, pulled) and b.volume == pytest.approx(1.0 + 5e-7, rel=tol.EXACT_REL)


def _case_geometries():
    """Each generator with its defaults and every generator table of cases/**/*.toml."""
    specs = [{"generator": n} for n in generators.GENERATORS if n not in ("boxes_on_platform", "outlines", "dxf", "meshes")]
    specs.append({"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0, 0], "size": [1, 1, 1]}]})
    for f in sorted(ROOT.glob("cases/**/*.toml")):
        geo = tomllib.loads(f.read_text()).get("case", {}).get("geometry")
        if isinstance(geo, dict) and isinstance(geo.get("file"), str):  # dxf: relative to the case file
            geo = dict(geo, file=str((f.parent / geo["file"]).resolve()))
        if isinstance(geo, dict) and isinstance(geo.get("folder"), str):  # outlines, meshes: the same
            geo = dict(geo, folder=str((f.parent / geo["folder"]).resolve()))
        if isinstance(geo, dict) and geo not in specs:
            specs.append(geo)
    specs += [{"generator": "tilt_wall", "seed": s, "depth_spread": d} for s in range(5) for d in (0.0, 1 / 3)]
    return specs


@pytest.mark.parametrize("spec", _case_geometries(), ids=lambda s: json.dumps(s, sort_keys=True))
def test_generated_geometries_have_only_corners(spec):
    """Every generated block (every part of a multi-part stone) is the distinct corners of
    its hull (parse checks it)."""
    bs = bf.parse(generators.generate(dict(spec)), f"generated {spec}")
    for b in bs.blocks:
        for part in b.parts:
            assert bf.not_convex(part) is None


def test_outline_points_on_an_edge_are_dropped_and_crossing_outlines_refused(tmp_path):
    """Repeated points and points on a straight edge are not corners: the outline reader
    drops them (the stone is the same); a self-crossing outline (a pentagram, all its
    turns convex) is refused naming the file and stone."""
    d = tmp_path / "w"
    d.mkdir()
    (d / "1.csv").write_text("0 0\n0.5 0\n1 0\n1 1\n1 1\n0 1\n0 0.4\n")
    bs = bf.parse(ol.make(d, thickness=0.4, fix_bottom=False))
    assert len(bs.block(1).vertices) == 8 and bs.block(1).volume == pytest.approx(0.4)
    star = [(np.cos(a), np.sin(a)) for a in np.pi / 2 + 4 * np.pi / 5 * np.arange(5)]
    (d / "1.csv").write_text("\n".join(f"{x} {z}" for x, z in star))
    with pytest.raises(ol.OutlineError, match=r"1\.csv \(stone 1\): stone outline crosses or touches itself"):
        ol.make(d, thickness=0.4, fix_bottom=False)


# --- 2. generator parameters ------------------------------------------------------------

@pytest.mark.parametrize("spec, words", [
    ({"generator": "running_bond", "courses": 0}, ["'running_bond'", "'courses'", "an integer >= 1", "got 0"]),
    ({"generator": "running_bond", "courses": 2.5}, ["'courses'", "an integer >= 1"]),
    ({"generator": "running_bond", "per_course": 1}, ["'per_course'", "an integer >= 2"]),
    ({"generator": "running_bond", "length": -1.0}, ["'length'", "> 0 m"]),
    ({"generator": "running_bond", "thickness": 0}, ["'thickness'", "> 0 m"]),
    ({"generator": "running_bond", "height": "4"}, ["'height'", "> 0 m", "got '4'"]),
    ({"generator": "running_bond", "colour": "red"}, ["'running_bond'", "unknown parameter(s) ['colour']", "allowed"]),
    ({"generator": "irregular_wall", "irregularity": 5}, ["'irregular_wall'", "'irregularity'", "in [0, 1)"]),
    ({"generator": "irregular_wall", "stone_length": [0.3, 0.2]}, ["'stone_length'", "0 < min < max"]),
    ({"generator": "irregular_wall", "stone_length": 0.2}, ["'stone_length'", "a list of 2"]),
    ({"generator": "irregular_wall", "courses": True}, ["'courses'", "integer"]),
    ({"generator": "irregular_wall", "seed": -1}, ["'seed'", "an integer >= 0"]),
    ({"generator": "irregular_wall", "stagger": 1.0}, ["'stagger'", "in [0, 1)"]),
    ({"generator": "irregular_wall", "stones_per_course": [3, 0]}, ["'stones_per_course'", "integers >= 1"]),
    ({"generator": "irregular_wall", "first_course": "platform"}, ["'first_course'", "['fixed', 'free']"]),
    ({"generator": "irregular_wall", "depth_spread": -0.1}, ["'depth_spread'", "in [0, 1)"]),
    ({"generator": "tilt_wall", "weight": 0}, ["'tilt_wall'", "'weight'", "> 0 N"]),
    ({"generator": "tilt_wall", "irregularity": 5}, ["'tilt_wall'", "'irregularity'", "in [0, 1)"]),
    ({"generator": "tilt_wall", "length": 2.0}, ["'tilt_wall'", "unknown parameter(s) ['length']"]),
    ({"generator": "tilt_wall", "density": 0.0}, ["'tilt_wall'", "'density'", "in [100, 100000] kg/m^3"]),
    ({"generator": "sacsayhuaman", "irregularity": 5}, ["'sacsayhuaman'", "'irregularity'", "in [0, 1)"]),
    ({"generator": "sacsayhuaman", "seed": "0"}, ["'sacsayhuaman'", "'seed'", "an integer >= 0"]),
    ({"generator": "four_blocks", "friction_angle_deg": 90}, ["'four_blocks'", "'friction_angle_deg'", "[0, 90)"]),
    ({"generator": "four_blocks", "density": 1e-300}, ["'four_blocks'", "'density'", "[100, 100000] kg/m^3"]),
    ({"generator": "four_blocks", "kn": -1}, ["'kn'", "> 0 N/m^3"]),
    ({"generator": "ogawa_blocks", "orientation": "sideways"},
     ["'ogawa_blocks'", "'orientation'", "['flat', 'upright']"]),
    ({"generator": "ogawa_blocks", "mu31": -0.1}, ["'ogawa_blocks'", "'mu31'", ">= 0"]),
    ({"generator": "ogawa_blocks", "damping": float("nan")}, ["'damping'", ">= 0"]),
    ({"generator": "boxes_on_platform"}, ["'boxes_on_platform'", "missing parameter(s) ['boxes']"]),
    ({"generator": "boxes_on_platform", "boxes": []}, ["'boxes'", "a non-empty list"]),
    ({"generator": "boxes_on_platform", "boxes": [{"id": 0, "center_xy": [0, 0], "size": [1, 1, 1]}]},
     ["'boxes[0].id'", "an integer >= 1"]),
    ({"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0, 0], "size": [1, 0, 1]}]},
     ["'boxes[0].size'", "each > 0"]),
    ({"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0, 0], "size": [1, 1, 1], "z": 1}]},
     ["'boxes[0]'", "keys id, center_xy, size"]),
    ({"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0, 0], "size": [1, 1, 1]}] * 2},
     ["'boxes[1].id'", "unique"]),
    ({"generator": "outlines", "folder": ".", "thickness": "0.8"}, ["'outlines'", "'thickness'", "> 0 m"]),
    ({"generator": "outlines", "folder": ".", "thickness": 0.8, "layout": "inca"}, ["'layout'", "'sacsayhuaman'"]),
    ({"generator": "walls"}, ["unknown geometry generator 'walls'", "known"]),
])
def test_bad_generator_parameters_are_named(spec, words):
    with pytest.raises(bf.GeometryError) as err:
        generators.generate(spec)
    assert all(w in str(err.value) for w in words), str(err.value)


def test_geometry_make_cli_reports_a_bad_parameter(tmp_path):
    out = tmp_path / "w.json"
    r = subprocess.run([sys.executable, "-m", "drystone.geometry", "make", "running_bond", str(out), "courses=0"],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 1 and "error: geometry generator 'running_bond': parameter 'courses'" in r.stderr
    assert "Traceback" not in r.stderr and not out.exists()


# --- 3. block-file values of the wrong type ---------------------------------------------

def _set(path, value):
    """A mutation setting d[path...] = value."""
    def f(d):
        *head, last = path
        for k in head:
            d = d[k]
        d[last] = value
    return f


@pytest.mark.parametrize("mutate, words", [
    (_set(["blocks", 1, "vertices", 0, 0], "0.1"),
     ["block 1: vertices contain '0.1', which is not a number: vertex 0"]),
    (_set(["blocks", 1, "vertices", 2, 1], True), ["block 1: vertices contain True", "vertex 2"]),
    (_set(["blocks", 1, "vertices", 3], [0.1, 0.2]), ["block 1: 'vertices': vertex 3 must be [x, y, z]"]),
    (_set(["blocks", 1, "vertices"], "box"), ["block 1: 'vertices' must be a list"]),
    (_set(["blocks", 1, "vertices", 0, 2], float("inf")), ["block 1: vertices contain a non-finite number"]),
    (_set(["blocks", 1, "id"], "1"), ["blocks[1]: 'id' must be an integer, got '1'"]),
    (_set(["blocks", 1, "id"], 1.0), ["blocks[1]: 'id' must be an integer, got 1.0"]),
    (_set(["blocks", 1, "id"], 10**12), ["blocks[1]: 'id' 1000000000000 is beyond 2147483647"]),
    (_set(["blocks", 1, "material"], ["stone"]), ["block 1: unknown material ['stone']"]),
    (_set(["blocks", 1, "label"], 5), ["block 1: 'label' must be a string"]),
    (_set(["control_points", 0, "position"], ["0", 0, 0.2]), ["control point 'top': 'position' contains '0'"]),
    (_set(["control_points", 0, "position"], [0, 0, float("nan")]),
     ["control point 'top': 'position' contains a non-finite number"]),
    (_set(["control_points", 0, "position"], [0, 0]), ["control point 'top': 'position' must be [x, y, z]"]),
    (_set(["control_points", 0, "block"], "1"), ["control point 'top': 'block' must be an integer block id, got '1'"]),
    (_set(["control_points", 0, "block"], 1.5), ["control point 'top': 'block' must be an integer", "1.5"]),
    (_set(["control_points", 0, "block"], True), ["control point 'top': 'block' must be an integer", "True"]),
    (_set(["control_points", 0, "name"], 3), ["control_points[0]: 'name' must be a non-empty string"]),
    (_set(["control_points"], {"name": "top"}), ["'control_points' must be a list"]),
    (_set(["joints", 0, "blocks"], ["1", 0]), ["joints[0]: 'blocks' must be two integer block ids"]),
    (_set(["joints", 0, "blocks"], [1.5, 0]), ["joints[0]: 'blocks' must be two integer block ids", "1.5"]),
    (_set(["joints", 0, "blocks"], [True, 0]), ["joints[0]: 'blocks' must be two integer block ids", "True"]),
    (_set(["joints", 0, "blocks"], [[1], 0]), ["joints[0]: 'blocks' must be two integer block ids"]),
    (_set(["joints", 0, "mu"], "0.5"), ["joints[0]: 'mu' must be a finite number, got '0.5'"]),
    (_set(["joints"], 5), ["'joints' must be a list"]),
    (_set(["materials", "stone", "density"], 1e-300), ["material 'stone': 'density' must be in [100, 100000] kg/m^3"]),
    (_set(["materials", "stone", "density"], 2.3), ["material 'stone': 'density' must be in [100, 100000]"]),
    (_set(["materials", "stone", "density"], 2.3e6), ["material 'stone': 'density' must be in [100, 100000]"]),
    (_set(["materials", "stone", "density"], "2300"), ["material 'stone': 'density' must be a finite number"]),
    (_set(["materials", "stone", "kn"], float("inf")), ["material 'stone': 'kn' must be a finite number"]),
    (_set(["version"], True), ["unsupported 'version' True"]),
])
def test_wrong_types_name_file_item_and_key(tmp_path, mutate, words):
    d = blocks_file(bf.box_vertices((0, 0, 0.1), (0.2, 0.3, 0.2)))
    mutate(d)
    msg = load_error(tmp_path, d)
    assert all(w in msg for w in words), msg


# --- 4. overlap test: sort and sweep ----------------------------------------------------

def grid(rows=40, cols=50, size=(0.2, 0.3, 0.1)):
    """rows x cols touching boxes (ids 1.. row by row, the first row fixed) on a platform."""
    sx, sy, sz = size
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((cols * sx / 2, 0, -0.05), (cols * sx + 1, 1, 0.1))}]
    for r in range(rows):
        for c in range(cols):
            blocks.append({"id": 1 + r * cols + c, "role": "fixed" if r == 0 else "free", "material": "stone",
                           "vertices": bf.box_vertices(((c + 0.5) * sx, 0, (r + 0.5) * sz), size)})
    return blocks_file(None, blocks=blocks, joints=[], control_points=[])


def test_2000_touching_blocks_no_overlap_and_one_overlap_named():
    d = grid()
    t = time.perf_counter()
    bs = bf.parse(d, "grid.json")
    print(f"\n2001 blocks: parse with the overlap test {time.perf_counter() - t:.2f} s")
    assert len(bs.blocks) == 2001
    t = time.perf_counter()
    bf.check_no_overlaps(bs, "grid.json")
    print(f"2001 blocks: check_no_overlaps alone {time.perf_counter() - t:.3f} s")
    k = 1 + 20 * 50 + 25  # row 20, column 25: its top raised 1 mm into the block above (k + 50)
    v = np.array(d["blocks"][k]["vertices"])
    v[v[:, 2] == v[:, 2].max(), 2] += 1e-3
    d["blocks"][k]["vertices"] = v.tolist()
    with pytest.raises(bf.GeometryError, match=rf"grid\.json: blocks {k} and {k + 50} interpenetrate by 0\.001 m"):
        bf.parse(d, "grid.json")


def _all_pairs(lo, hi, tol):
    n = len(lo)
    return [(i, j) for i in range(n) for j in range(i + 1, n)
            if np.all(lo[i] < hi[j] - tol) and np.all(lo[j] < hi[i] - tol)]


def _old_check(bs, where, tol=bf.OVERLAP_TOL):
    """The former all-pairs check_no_overlaps, for comparison."""
    lo = np.array([b.vertices.min(axis=0) for b in bs.blocks])
    hi = np.array([b.vertices.max(axis=0) for b in bs.blocks])
    for i, j in _all_pairs(lo, hi, tol):
        a, b = bs.blocks[i], bs.blocks[j]
        if a.role != "free" and b.role != "free":
            continue
        t = ph.overlap_thickness(a.vertices, b.vertices)
        if t > tol:
            raise bf.GeometryError(f"{where}: blocks {a.id} and {b.id} interpenetrate by {t:.3g} m "
                                   f"(tolerance {tol:g} m)")


def test_sweep_finds_the_same_pairs_and_errors_as_all_pairs():
    rng = np.random.default_rng(0)
    lo = rng.uniform(0, 10, (400, 3))
    lo[:100] = np.round(lo[:100])  # some boxes exactly touching
    hi = lo + rng.uniform(0.1, 1.5, (400, 3))
    hi[:100] = lo[:100] + 1.0
    for tol in (0.0, bf.OVERLAP_TOL, 0.3):
        assert bf.candidate_pairs(lo, hi, tol) == _all_pairs(lo, hi, tol)
    for trial in range(30):
        n = int(rng.integers(2, 25))
        blocks = []
        for k in range(n):
            v = np.array(bf.box_vertices((0, 0, 0), rng.uniform(0.05, 0.8, 3)))
            if trial % 2:  # turned boxes: bounding boxes overlap, faces may still separate
                v = v @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
            blocks.append({"id": 100 - k, "role": str(rng.choice(["free", "fixed", "platform"], p=[0.6, 0.3, 0.1])),
                           "material": "stone", "vertices": (v + rng.uniform(0, 4, 3)).tolist()})
        blocks[0]["role"] = "free"
        blocks[-1]["role"] = "fixed"  # a geometry needs something that holds its free blocks
        bs = bf.parse(blocks_file(None, blocks=blocks, joints=[], control_points=[]), "r", check_overlaps=False)
        errors = []
        for check in (_old_check, bf.check_no_overlaps):
            try:
                check(bs, "r")
                errors.append(None)
            except bf.GeometryError as exc:
                errors.append(str(exc))
        assert errors[0] == errors[1]


# --- drawings and scans: wrong units, hovering fixed blocks, refusals from the command line --

def _outline_wall(folder, scale):
    """Three 0.45 x 0.3 (x scale) stones, two side by side and one on top, as outline files."""
    folder.mkdir()
    for bid, (x, z) in {1: (0, 0), 2: (0.45, 0), 3: (0.2, 0.3)}.items():
        pts = [(x, z), (x + 0.45, z), (x + 0.45, z + 0.3), (x, z + 0.3)]
        (folder / f"{bid}.csv").write_text("".join(f"{px * scale!r} {pz * scale!r}\n" for px, pz in pts))
    return folder


@pytest.mark.parametrize("scale, words", [
    (1.0, None),
    (0.001 * 2 / 0.9, ["the wall is 0.002 m across", "outside the plausible 0.1-500 m",
                       "stone(s) outside the plausible 0.02-20 m"]),  # a 0.9 m wall drawn in mm read as m
    (2000 / 0.9, ["the wall is 2e+03 m across", "outside the plausible 0.1-500 m", "e.g. "]),
])
def test_wrong_units_warn_stating_the_range(tmp_path, capsys, scale, words):
    """A 2 mm or 2 km wall ran without a word: a `warning:` line on stderr states the size and
    the plausible range (drystone/geometry/plausible.py); the geometry is still built."""
    d = ol.make(_outline_wall(tmp_path / "w", scale), thickness=0.5 * scale)
    assert len(d["blocks"]) == 4
    err = capsys.readouterr().err
    if words is None:
        assert "warning" not in err
    else:
        assert err.startswith("warning: ") and all(w in err for w in words), err
        assert all(line.startswith("warning: ") for line in err.splitlines())


def test_absurd_size_refused_naming_the_file_not_the_platform(tmp_path):
    """A drawing of 1e20 mm was refused as 'block 0: vertices are coplanar' (the package's own
    0.1 m platform lost in the round-off): now refused for its size, naming the file."""
    with pytest.raises(bf.GeometryError, match=r"outlines in .*w: the wall is 9e\+16 m across, beyond any "
                                               r"structure \(at most 100000 m"):
        ol.make(_outline_wall(tmp_path / "w", 1e17), thickness=0.5)


def test_fixed_blocks_held_in_mid_air_are_listed():
    """A fixed block 1 m above the platform touches neither it nor a fixed block that does: a
    run warns (resolve); one on the platform, or on a fixed block on it, is not listed, nor
    are the four-block model's supports (no platform: the fixed blocks are the ground)."""
    def fixed_at(z):
        return {"id": 2, "role": "fixed", "material": "stone", "vertices": bf.box_vertices((0, 0, z), (0.2, 0.2, 0.2))}
    base = blocks_file(bf.box_vertices((1, 0, 0.1), (0.2, 0.2, 0.2)), joints=[], control_points=[])
    for z, want in ((1.1, [2]), (0.1, []), (0.1 + 0.5 * bf.STANDING_TOL, []), (0.1 + 2 * bf.STANDING_TOL, [2])):
        d = dict(base, blocks=base["blocks"] + [fixed_at(z)])
        assert bf.hovering_fixed(bf.parse(d)) == want, z
    chain = dict(base, blocks=base["blocks"] + [fixed_at(0.1), dict(fixed_at(0.3), id=3)])
    assert bf.hovering_fixed(bf.parse(chain)) == []
    assert bf.hovering_fixed(bf.parse(generators.generate({"generator": "four_blocks"}))) == []


def test_bad_drawing_refused_by_run_before_anything_is_written(tmp_path):
    """From the command line: a stone drawn as a CIRCLE on the stones layer is one line naming
    the drawing, the handle and the type, exit 2, before the run (nothing in --out)."""
    ezdxf = pytest.importorskip("ezdxf")
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    msp.add_lwpolyline([(0, 0), (0.45, 0), (0.45, 0.3), (0, 0.3)], close=True, dxfattribs={"layer": "stones"})
    msp.add_text("1").set_placement((0.2, 0.15))
    h = msp.add_circle((0.2, 0.5), 0.15, dxfattribs={"layer": "stones"}).dxf.handle
    doc.saveas(tmp_path / "wall.dxf")
    (tmp_path / "c.toml").write_text('[case]\nname = "dxfwall"\n'
                                     'geometry = {generator = "dxf", file = "wall.dxf", thickness = 0.5}\n'
                                     '[[stages]]\ntype = "gravity"\nduration = 0.1\n')
    r = subprocess.run([sys.executable, "-m", "drystone", "run", str(tmp_path / "c.toml"), "--out",
                        str(tmp_path / "out")], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in r.stderr
    assert f"wall.dxf: CIRCLE handle {h} on layer 'stones' cannot be read" in lines[0]
    assert not (tmp_path / "out").exists()


def test_resolving_a_run_warns_of_a_fixed_block_in_mid_air(tmp_path, capsys):
    """A block file whose fixed block is 1 m above the platform: the run's resolution prints
    one `warning:` line naming the file and the block (before YADE); on the platform, none."""
    from drystone import runner
    from drystone.model import case as casemod

    for z, warned in ((1.1, True), (0.1, False)):
        d = blocks_file(bf.box_vertices((0, 0, z + 0.2), (0.2, 0.2, 0.2)), joints=[], control_points=[])
        d["blocks"].append({"id": 2, "role": "fixed", "material": "stone",
                            "vertices": bf.box_vertices((0, 0, z), (0.2, 0.2, 0.2))})
        (tmp_path / "g.json").write_text(json.dumps(d))
        (tmp_path / "c.toml").write_text('[case]\ngeometry = "g.json"\n[[stages]]\ntype = "gravity"\nduration = 0.1\n')
        p = tmp_path / "c.toml"
        runner.resolve(casemod.load(p), str(p), tmp_path / f"out{z}")
        err = capsys.readouterr().err
        if warned:
            assert err.startswith("warning: ") and "g.json: fixed block(s) [2] stand neither on the platform" in err
            assert len(err.strip().splitlines()) == 1
        else:
            assert "warning" not in err
