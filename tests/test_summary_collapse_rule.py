"""summary.json's per-stone ``collapsed`` and the run's console follow the package's one
collapse rule (drystone/mechanics/collapse.py ``run_stones``, as the analyses' ``outcome``):
on synthetic histories of four 0.2 m cubes (displacement threshold 0.1 m) a stone that slid
0.15 m along the wall is in-plane sliding and beyond the displacement threshold (damage),
not collapsed; one pushed 0.15 m out of plane collapsed (out_of_plane); one tipped past 45
deg overturned; one that only settled 5 mm during gravity stands (the rule measures from the
end of gravity)."""
from __future__ import annotations

import json

import numpy as np
from scipy.spatial.transform import Rotation

from drystone.analyses import common
from drystone.geometry.simple import boxes_on_platform
from drystone.postprocess import console
from drystone.postprocess import summary as summ


def _four_cubes(n=51):
    boxes = [{"id": i + 1, "center_xy": [0.5 * i, 0.0], "size": [0.2, 0.2, 0.2]} for i in range(4)]
    blocks = boxes_on_platform(boxes)["blocks"]
    t = np.linspace(0.0, 2.0, n)
    pos0 = np.array([[0.5 * i, 0.0, 0.1] for i in range(4)])
    pos = np.repeat(pos0[None], n, axis=0)
    quat = np.tile([0, 0, 0, 1.0], (n, 4, 1))
    late = t > 1.0
    ramp = np.clip((t - 1.0) / 0.5, 0.0, 1.0)
    pos[:, 0, 0] += 0.15 * ramp                        # 1: along the wall
    pos[:, 1, 1] += 0.15 * ramp                        # 2: out of plane
    q = Rotation.from_rotvec(np.outer(ramp, [0.9, 0.0, 0.0])).as_quat()  # 3: 52 deg about x (tips at 45)
    quat[:, 2] = q
    pos[t <= 0.5, 3, 2] -= 0.005 * t[t <= 0.5] / 0.5  # 4: settles 5 mm in gravity, then stays
    pos[t > 0.5, 3, 2] -= 0.005
    assert late.any()
    h = {"t": t, "block_ids": np.array([1, 2, 3, 4]), "pos": pos, "pos0": pos0, "quat": quat,
         "quat0": np.tile([0, 0, 0, 1.0], (4, 1)), "cp": np.zeros((n, 0, 3)), "cp0": np.zeros((0, 3)),
         "cp_names": np.array([])}
    spec = {"blocks": blocks, "collapse_threshold": {str(i + 1): 0.1 for i in range(4)}, "control_points": [],
            "stages": [{"type": "gravity", "start": 0.0, "end": 0.5, "params": {}},
                       {"type": "excitation", "start": 0.5, "end": 2.0, "params": {}}]}
    return spec, h


def test_summary_collapsed_is_the_one_rule_and_residuals_are_damage(tmp_path):
    spec, h = _four_cubes()
    b = summ.block_table(spec, h, {})
    assert not b["1"]["collapsed"] and b["1"]["in_plane_sliding"] and b["1"]["beyond_displacement_threshold"]
    assert b["2"]["collapsed"] and b["2"]["collapse_why"] == ["out_of_plane"] and not b["2"]["fell"]
    assert b["3"]["collapsed"] and b["3"]["collapse_why"] == ["overturned"]
    assert not b["4"]["collapsed"] and not b["4"]["beyond_displacement_threshold"]
    text = "\n".join(console.lines({"name": "x", "run": {}, "blocks": b, "inputs": {}}, spec))
    assert "collapsed stones (left the model, fell, overturned or out of plane): 2 of 4 (2 out_of_plane, " \
           "3 overturned)" in text
    assert "in-plane sliding (damage, not collapse): stone 1" in text

    # the analyses' outcome reads the same run the same way
    d = tmp_path / "run"
    d.mkdir()
    np.savez(d / "histories.npz", **{k: v for k, v in h.items()})
    (d / "spec.json").write_text(json.dumps(spec))
    (d / "summary.json").write_text(json.dumps({"blocks": b, "run": {}}))
    o = common.outcome(d)
    assert o["status"] == "done", o
    assert o["collapsed_stones"] == sorted(int(k) for k, r in b.items() if r["collapsed"])
    assert o["in_plane_sliding"] == [1]
