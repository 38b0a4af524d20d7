"""User outlines extruded to blocks (drystone/geometry/outlines.py)."""
import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.geometry import outlines as ol
from drystone.geometry import polyhedron as ph
from drystone.geometry import sacsayhuaman as sw


def write(folder, name, text):
    folder.mkdir(exist_ok=True)
    (folder / name).write_text(text)


def test_two_stones_extruded_with_platform(tmp_path):
    d = tmp_path / "w"
    write(d, "1.csv", "x,z\n0,0\n1,0\n1,0.5\n0,0.5\n")
    write(d, "2.txt", "# top stone, clockwise on purpose\n0 0.5\n0 1\n1 1\n1 0.5\n")
    data = ol.make(d, thickness=0.4)
    bs = bf.parse(data)
    assert bs.ids("fixed") == [1] and bs.ids("free") == [2]
    assert bs.block(2).volume == pytest.approx(0.5 * 0.4)
    v = bs.block(2).vertices
    assert v[:, 1].min() == pytest.approx(-0.2) and v[:, 1].max() == pytest.approx(0.2)
    assert bs.block(0).role == "platform" and bs.block(0).vertices[:, 2].max() == pytest.approx(0.0)


@pytest.mark.parametrize("name, text, match", [
    ("3.csv", "0 0\n1 1\n1 0\n0 1\n", r"3\.csv \(stone 3\): stone outline crosses or touches itself"),
    ("3.csv", "0 0\n1 0\n1 1\n2 1\n2 2\n1 2\n1 1\n0 1\n", r"\(stone 3\): .*coincide .*pinched"),
    ("3.csv", "0 0\n1 0\n0.5 1e-7\n", r"\(stone 3\): the outline has no area"),
    ("3.csv", "0 0\n1 0\nabc def\n", r"3\.csv:3"),
    ("3.csv", "0 0\n1 0\n", "at least 3"),
    ("x.csv", "0 0\n1 0\n1 1\n", "named by the stone's id"),
])
def test_bad_outlines_name_the_file(tmp_path, name, text, match):
    write(tmp_path / "w", name, text)
    with pytest.raises(ol.OutlineError, match=match):
        ol.make(tmp_path / "w", thickness=0.5)


def test_sacsayhuaman_layout_round_trip(tmp_path):
    """The generated section's front faces written as outline files come back as the same
    40 stones with the paper's roles and control points."""
    ref = sw.make(seed=2)
    d = tmp_path / "stones"
    for b in ref["blocks"][1:]:
        v = np.asarray(b["vertices"])
        front = v[np.isclose(v[:, 1], v[:, 1].min())][:, [0, 2]]
        c = front.mean(axis=0)
        front = front[np.argsort(np.arctan2(front[:, 1] - c[1], front[:, 0] - c[0]))]
        write(d, f"{b['id']}.csv", "\n".join(f"{x:.12f},{z:.12f}" for x, z in front))
    data = ol.make(d, thickness=0.8, layout="sacsayhuaman")
    got, want = bf.parse(data), bf.parse(ref)
    for bid in range(1, 41):
        assert got.block(bid).volume == pytest.approx(want.block(bid).volume, rel=tol.NUMERICAL_REL)
        assert got.block(bid).role == want.block(bid).role
        assert got.block(bid).blocked_dofs == want.block(bid).blocked_dofs
    assert {c["name"]: c["block"] for c in data["control_points"]} == {"A": 35, "B": 38, "C": 39, "D": 40}


L_TEXT = "0 0\n2 0\n2 1\n1 1\n1 2\n0 2\n"  # x z, m: an L, re-entrant corner (1, 1)


def test_convex_outlines_keep_version_1_and_one_vertex_list(tmp_path):
    d = tmp_path / "w"
    write(d, "1.csv", "0 0\n1 0\n1 0.5\n0 0.5\n")
    data = ol.make(d, thickness=0.4, fix_bottom=False)
    assert data["version"] == 1 and "parts" not in data["blocks"][1]
    assert data["blocks"][1]["vertices"] == [[0.0, -0.2, 0.0], [0.0, 0.2, 0.0], [1.0, -0.2, 0.0], [1.0, 0.2, 0.0],
                                             [1.0, -0.2, 0.5], [1.0, 0.2, 0.5], [0.0, -0.2, 0.5], [0.0, 0.2, 0.5]]


def test_re_entrant_outline_becomes_one_stone_of_convex_parts(tmp_path):
    """An L outline: one stone (id 2) of two extruded convex parts (the minimum), version 2,
    the parts' volumes summing to the L's area x thickness; the convex stone beside it
    keeps its vertex list."""
    d = tmp_path / "w"
    write(d, "1.csv", "0 -1\n2 -1\n2 0\n0 0\n")
    write(d, "2.csv", L_TEXT)
    data = ol.make(d, thickness=0.4)
    assert data["version"] == bf.PARTS_VERSION
    one, two = data["blocks"][1], data["blocks"][2]
    assert "vertices" in one and "parts" not in one
    assert "vertices" not in two and len(two["parts"]) == 2
    area = 0.0
    for part in two["parts"]:
        v = np.asarray(part)
        assert sorted(set(v[:, 1])) == [-0.2, 0.2] and len(v) == 2 * len(set(map(tuple, v[:, [0, 2]])))
        front = v[v[:, 1] < 0][:, [0, 2]]
        area += 0.5 * abs(np.sum(front[:, 0] * np.roll(front[:, 1], -1) - np.roll(front[:, 0], -1) * front[:, 1]))
    assert area == pytest.approx(3.0, rel=tol.EXACT_REL)
    bs = bf.parse(data)
    assert bs.ids("fixed") == [1] and bs.ids("free") == [2]
    assert sum(ph.volume_centroid(p)[0] for p in bs.block(2).parts) == pytest.approx(3.0 * 0.4, rel=tol.NUMERICAL_REL)


def test_notched_outline_once_refused_is_a_two_part_stone(tmp_path):
    """The re-entrant pentagon this file used to refuse ("not convex"): two parts now,
    their volumes summing to its area (the square less the notch 0.5 x 1 x 0.5: 0.75 m^2) x thickness."""
    d = tmp_path / "w"
    write(d, "3.csv", "0 0\n1 0\n0.5 0.2\n1 1\n0 1\n")
    bs = bf.parse(ol.make(d, thickness=0.5, fix_bottom=False))
    parts = bs.block(3).parts
    assert len(parts) == 2
    assert sum(ph.volume_centroid(p)[0] for p in parts) == pytest.approx(0.75 * 0.5, rel=tol.NUMERICAL_REL)


@pytest.mark.parametrize("name, raw, match", [
    ("1.csv", "0 0\n1 0\n1 1\n0 1\n# caf\xe9\n".encode("latin-1"),
     r"1\.csv: not a UTF-8 text file \(byte 0xe9 at position 21\)"),
    ("².txt", b"0 0\n1 0\n1 1\n0 1\n", r"².txt: outline files are named by the stone's id, an integer from 1 to "
                                       r"2147483647 in the digits 0-9"),
    ("1" * 40 + ".txt", b"0 0\n1 0\n1 1\n0 1\n", r"1{40}\.txt: outline files are named by the stone's id"),
])
def test_unreadable_names_and_encodings_are_refused(tmp_path, name, raw, match):
    """A latin-1 file and a file named '².txt' were tracebacks (UnicodeDecodeError, int('²'));
    a 40-digit id was accepted and broke the run's outputs at the end."""
    d = tmp_path / "w"
    write(d, "2.csv", "0 1\n1 1\n1 2\n0 2\n")
    (d / name).write_bytes(raw)
    with pytest.raises(ol.OutlineError, match=match) as err:
        ol.make(d, thickness=0.4)
    assert "\n" not in str(err.value)
