"""Block-definition format: good and bad inputs, errors that name file, block, problem."""
import json
import subprocess
import sys

import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.geometry import four_blocks
from drystone.geometry import polyhedron as ph


def one_block(**over):
    d = {"format": bf.FORMAT, "version": 1, "name": "t",
         "materials": {"stone": {"density": 2300, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}},
         "blocks": [{"id": 0, "role": "platform", "material": "stone",
                     "vertices": bf.box_vertices((0, 0, -0.05), (1, 1, 0.1))},
                    {"id": 7, "role": "free", "material": "stone",
                     "vertices": bf.box_vertices((0, 0, 0.1), (0.2, 0.3, 0.2))}]}
    d.update(over)
    return d


def test_box_volume_and_centroid_exact():
    v, c = ph.volume_centroid(bf.box_vertices((1, 2, 3), (0.2, 0.3, 0.4)))
    assert v == pytest.approx(0.024, rel=tol.EXACT_REL)
    assert np.allclose(c, (1, 2, 3), atol=tol.EXACT_ABS)


def test_good_file_round_trip(tmp_path):
    p = bf.write(one_block(), tmp_path / "g.json")
    bs = bf.load(p)
    assert bs.ids("free") == [7]
    assert bs.mass(7) == pytest.approx(2300 * 0.2 * 0.3 * 0.2)


def test_four_blocks_weights_match_paper():
    """Paper §3.1: 0.220 x 0.105 x 0.050 m at 2200 kg/m^3 weigh 24.93 N each."""
    bs = bf.parse(four_blocks.make())
    for b in (1, 2):
        assert bs.mass(b) * 9.81 == pytest.approx(24.93, abs=tol.PRINTED_2_DECIMALS)
    assert bs.materials["stone"].mu == pytest.approx(np.tan(np.radians(38)))


@pytest.mark.parametrize("mutate, message", [
    (lambda d: d["blocks"][1].update(vertices=bf.box_vertices((0, 0, 0.1), (0.2, 0.3, 0.2)) + [[0, 0, 0.1]]),
     "block 7: not convex"),
    (lambda d: d["blocks"][1].update(vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
     "block 7: vertices are coplanar"),
    (lambda d: d["blocks"][1].update(vertices=bf.box_vertices((0, 0, 0.09), (0.2, 0.3, 0.2))),
     "blocks 0 and 7 interpenetrate"),
    (lambda d: d["blocks"][1]["vertices"][0].__setitem__(0, float("nan")), "block 7: vertices contain a non-finite"),
    (lambda d: d["materials"]["stone"].update(kn=-1.0), "material 'stone': 'kn' must be > 0"),
    (lambda d: d["blocks"][1].update(role="loose"), "block 7: 'role' must be one of"),
    (lambda d: d["blocks"][1].update(material="granite"), "block 7: unknown material 'granite'"),
    (lambda d: d["blocks"][1].update(colour="red"), "block 7: unknown key(s) ['colour']"),
    (lambda d: d["blocks"].append(dict(d["blocks"][1])), "block 7: duplicate id"),
    (lambda d: d.update(units={"length": "mm", "mass": "kg"}), "'units' must be"),
])
def test_bad_input_names_block_and_problem(tmp_path, mutate, message):
    d = one_block()
    mutate(d)
    target = tmp_path / "bad.json"
    with pytest.raises(bf.GeometryError) as err:
        bf.write(d, target)
    assert message in str(err.value)
    assert str(target) in str(err.value)
    assert not target.exists(), "nothing may be written when validation fails"


def test_touching_blocks_are_accepted():
    """Blocks sharing a face exactly (overlap 0) are valid: both are kept, their overlap
    thickness is zero and the overlap check passes."""
    bs = bf.parse(one_block())
    assert sorted(bs.ids()) == [0, 7]
    assert ph.overlap_thickness(bs.block(0).vertices, bs.block(7).vertices) == 0.0
    bf.check_no_overlaps(bs, "t")  # raises GeometryError on an overlap


def test_overlap_thickness_is_the_penetration():
    a = bf.box_vertices((0, 0, 0), (1, 1, 1))
    b = bf.box_vertices((0, 0, 1 - 1e-3), (0.5, 0.5, 1))
    assert ph.overlap_thickness(a, b) == pytest.approx(1e-3, rel=tol.LP_THICKNESS_REL)
    assert ph.overlap_thickness(a, bf.box_vertices((0, 0, 2), (1, 1, 1))) == 0.0


def test_cli_validate_exit_code(tmp_path):
    good = bf.write(one_block(), tmp_path / "good.json")
    bad = tmp_path / "bad.json"
    d = one_block()
    d["blocks"][1]["vertices"] = bf.box_vertices((0, 0, 0.0), (0.2, 0.3, 0.2))
    bad.write_text(json.dumps(d))
    ok = subprocess.run([sys.executable, "-m", "drystone.geometry", "validate", str(good)], capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    ko = subprocess.run([sys.executable, "-m", "drystone.geometry", "validate", str(bad)], capture_output=True, text=True)
    assert ko.returncode != 0
    assert "blocks 0 and 7 interpenetrate" in ko.stderr and str(bad) in ko.stderr
