"""The friction-study driver end to end on a short record (1D model)."""
import json

import numpy as np

from ogawa import study
from motions import catalogue, processing


def test_study_short_record(tmp_path):
    """4 s of the Kobe record, 2 runs, 3 random sets: every set has finite residuals below
    a physical bound (a block cannot slide farther than the base moves relative to a fixed
    point, |u| <= integral of |v_base|, plus a margin for the rest), the summary and report
    are written, and the random-study fractions are consistent counts."""
    rec = processing.trim(processing.scale_to_pga(catalogue.get("kobe1995"), pga_g=0.818), 3.0, 7.0)
    s = study.run(n_random=3, runs=2, substeps=5, record=rec, workers=2, out=tmp_path, progress=False)
    vb = np.cumsum(rec.acc) * rec.dt
    bound_mm = 1e3 * 2 * np.sum(np.abs(vb)) * rec.dt * 2  # 2 runs, factor 2 margin
    for name, res in s["sets"].items():
        r = np.asarray(res["1d"])
        assert r.shape == (2, 5) and np.all(np.isfinite(r))
        assert np.abs(r).max() < bound_mm, name
    rs = s["random_study"]
    assert rs["n_sets"] == 3 and rs["rougher_base"]["n_sets"] + rs["smoother_base"]["n_sets"] == 3
    assert json.loads((tmp_path / "summary.json").read_text())["runs"] == 2
    assert (tmp_path / "report.md").is_file() and (tmp_path / "table4_run1.png").is_file()


def test_sets_reproducible_and_table4():
    a, b = study.friction_sets(5), study.friction_sets(5)
    assert a == b
    assert a["table4_run2"] == {"mu10": 0.47, "mu20": 0.30, "mu31": 0.50, "mu41": 0.39, "mu42": 0.32, "mu52": 0.35}
    assert all(abs(v - 0.4) <= 0.02 for v in a["uniform_pm0.02"].values())


def test_experimental_pattern():
    assert study.experimental_pattern([10, 2, 25, 20, 8])
    assert not study.experimental_pattern([30, 2, 25, 20, 8])


def test_experimental_pattern_with_fallen_blocks():
    """A block that fell off (None) counts as moving most; ties at the top are no pattern."""
    from ogawa.study import experimental_pattern
    assert experimental_pattern([1.0, 0.5, 5.0, 4.0, 2.0])
    assert experimental_pattern([1.0, 0.5, None, None, 2.0])
    assert not experimental_pattern([1.0, 0.5, None, None, None])  # block 5 fell too: no order among them
    assert not experimental_pattern([1.0, 1.0, 5.0, 4.0, 2.0])  # block 2 not the least alone
