"""Issue 25, item 7: ``geometry/split.py`` ``split_parts``, a multi-part stone (block file
version 2) cut into independent convex blocks, one per part: the shape study's (c')
walls. Checked on an L- and a T-shaped stone: ids, roles, dofs, labels, joints, control
points, volume and centroid (exact: the parts are boxes), and on a generated polygonal
wall (weight and validity)."""
import copy

import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.geometry import polygonal_wall
from drystone.geometry.split import split_parts


def box(lo, hi):
    return [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]


#: an L (foot and leg, joined over the face z = 0.1) and a T (stem and two arms)
L_PARTS = [box((0, 0, 0), (0.4, 0.2, 0.1)), box((0, 0, 0.1), (0.1, 0.2, 0.4))]
T_PARTS = [box((1.05, 0, 0), (1.15, 0.2, 0.4)), box((0.85, 0, 0.3), (1.05, 0.2, 0.4)),
           box((1.15, 0, 0.3), (1.35, 0.2, 0.4))]


def wall():
    """Platform 0, the L (id 3, free, held "xY"), a convex box (id 9, fixed) and the T (id 5)."""
    return {"format": bf.FORMAT, "version": 2, "name": "w", "description": "two hooked stones",
            "materials": {"stone": {"density": 2000.0, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}},
            "blocks": [{"id": 0, "role": "platform", "material": "stone", "vertices": box((-1, -1, -0.1), (3, 1, 0))},
                       {"id": 3, "role": "free", "material": "stone", "parts": L_PARTS, "blocked_dofs": "xY",
                        "label": "L"},
                       {"id": 9, "role": "fixed", "material": "stone", "vertices": box((2, 0, 0), (2.2, 0.2, 0.2))},
                       {"id": 5, "role": "free", "material": "stone", "parts": T_PARTS}],
            "joints": [{"blocks": [3, 5], "mu": 0.6}, {"blocks": [9, 0], "damping": 0.5}],
            "control_points": [{"name": "leg", "block": 3, "position": [0.05, 0.1, 0.4]},
                               {"name": "arm", "block": 5, "position": [1.3, 0.1, 0.4]},
                               {"name": "box", "block": 9, "position": [2.1, 0.1, 0.2]}]}


def test_split_gives_one_block_per_part():
    d = wall()
    before = copy.deepcopy(d)
    s = split_parts(d, "wall")
    assert d == before  # the input is not changed
    bs = bf.parse(s, "split", check_overlaps=True)
    assert s["version"] == bf.VERSION  # every block one part now
    assert [b.id for b in bs.blocks] == [0, 3, 10, 9, 5, 11, 12]  # first part keeps the id, new ids after 9
    assert s["generator"]["split"] == {"stones": {"3": [3, 10], "5": [5, 11, 12]}, "blocks_before": 4,
                                       "blocks_after": 7}
    by = {b.id: b for b in bs.blocks}
    for bid, part in zip((3, 10), L_PARTS):
        assert np.array_equal(by[bid].vertices, np.asarray(part, float))
        assert (by[bid].role, by[bid].blocked_dofs) == ("free", "xY")
    assert by[10].label == "stone 3 part 2 of 2: L" and by[11].label == "stone 5 part 2 of 3"
    assert (by[9].role, by[9].label) == ("fixed", "")
    # a joint naming a split stone holds for every part of it
    assert sorted(tuple(j["blocks"]) for j in s["joints"] if j.get("mu") == 0.6) == \
        [(3, 5), (3, 11), (3, 12), (10, 5), (10, 11), (10, 12)]
    assert {"blocks": [9, 0], "damping": 0.5} in s["joints"]
    # control points go to the part that holds them
    cps = {c["name"]: c["block"] for c in s["control_points"]}
    assert cps == {"leg": 10, "arm": 12, "box": 9}


def test_split_keeps_volume_and_centroid():
    """The parts tile the stone: total volume and the centroid of the split blocks (volume
    weighted) are the union's, exactly for boxes (round-off)."""
    whole = bf.parse(wall(), "wall")
    cut = bf.parse(split_parts(wall()), "split")
    for stone, parts in ((3, (3, 10)), (5, (5, 11, 12))):
        u = whole.block(stone)
        v = sum(cut.block(p).volume for p in parts)
        c = sum(cut.block(p).volume * cut.block(p).centroid for p in parts) / v
        assert v == pytest.approx(u.volume, rel=tol.EXACT_REL)
        assert np.allclose(c, u.centroid, rtol=0, atol=tol.EXACT_ABS)
    assert u.volume == pytest.approx(0.1 * 0.2 * 0.4 + 2 * 0.2 * 0.2 * 0.1, rel=tol.EXACT_REL)  # the T


def test_file_without_parts_comes_back_unchanged():
    d = wall()
    d["blocks"] = [b for b in d["blocks"] if "parts" not in b] + [
        {"id": 4, "role": "free", "material": "stone", "vertices": box((0, 0, 0), (0.4, 0.2, 0.1))}]
    d["joints"], d["control_points"], d["version"] = [d["joints"][1]], [d["control_points"][2]], 1
    assert split_parts(d) == d


def test_bad_input_is_refused_naming_it():
    d = wall()
    d["blocks"][1]["parts"][1] = box((0, 0, 0.05), (0.1, 0.2, 0.4))  # overlaps the foot
    with pytest.raises(bf.GeometryError, match="wall.json: block 3"):
        split_parts(d, "wall.json")


def test_polygonal_wall_split_keeps_weight():
    """A generated interlocking wall: its multi-part stones become blocks of the same total
    weight; the result validates with the overlap check."""
    d = polygonal_wall.make(length=3.0, height=1.5, thickness=0.4, stone_size=(0.3, 0.8), seed=1, reentrant=0.5,
                            typology="uniform")
    multi = [b for b in d["blocks"] if "parts" in b]
    assert multi  # the generator made re-entrant stones
    s = split_parts(d, "generated")
    a, b = bf.parse(d, "d"), bf.parse(s, "s", check_overlaps=True)
    assert len(b.blocks) == len(a.blocks) + sum(len(x["parts"]) - 1 for x in multi)
    assert sum(b.mass(x.id) for x in b.blocks) == pytest.approx(sum(a.mass(x.id) for x in a.blocks),
                                                               rel=tol.EXACT_REL)
