"""The two readings of Ogawa et al.'s "100x50x100 mm" blocks (drystone/geometry/ogawa_blocks.py)."""
import numpy as np
import pytest

import tolerances as tol
from drystone.geometry import blockfile as bf
from drystone.geometry import ogawa_blocks as ob


def _dims(d):
    return {b["id"]: np.ptp(np.asarray(b["vertices"]), axis=0) for b in d["blocks"] if b["role"] == "free"}


@pytest.mark.parametrize("orientation, size_big, size_end", [
    ("upright", (0.100, 0.050, 0.100), (0.050, 0.050, 0.100)),  # length x thickness x height
    ("flat", (0.100, 0.100, 0.050), (0.050, 0.100, 0.050)),  # length x depth x height
])
def test_readings(orientation, size_big, size_end):
    """Blocks 1, 2, 4 and the end blocks 3, 5 have the paper's sizes in the named axis
    order (exact to round-off: 1e-12 m), the stack is valid (no overlaps, convex) and
    the reading is labelled as assumed in the generator entry."""
    d = ob.make(orientation=orientation)
    bs = bf.parse(d, orientation)
    assert sorted(bs.ids("free")) == [1, 2, 3, 4, 5]
    dims = _dims(d)
    for b in (1, 2, 4):
        assert dims[b] == pytest.approx(size_big, abs=tol.EXACT_ABS)
    for b in ob.END_BLOCKS:
        assert dims[b] == pytest.approx(size_end, abs=tol.EXACT_ABS)
    g = d["generator"]
    assert g["orientation"] == orientation and any("ASSUMED" in a for a in g["assumed"])
    assert ob.ASSUMED[orientation] in g["assumed"]


def test_same_volumes_and_layout_in_both_readings():
    """Both readings have the same block volumes (so the same masses) and the same layout
    along x; only the end blocks' slenderness changes (height / length 2 against 1)."""
    up, flat = _dims(ob.make()), _dims(ob.make(orientation="flat"))
    for b in range(1, 6):
        assert np.prod(up[b]) == pytest.approx(np.prod(flat[b]), rel=tol.EXACT_REL)
        assert up[b][0] == pytest.approx(flat[b][0], abs=tol.EXACT_ABS)
    assert up[3][2] / up[3][0] == pytest.approx(2.0) and flat[3][2] / flat[3][0] == pytest.approx(1.0)


def test_unknown_orientation_is_refused():
    with pytest.raises(ValueError, match="orientation"):
        ob.make(orientation="sideways")
