"""The friction-study driver end to end on a short record (1D model)."""
import json

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure
from drystone.studies.ogawa import study
from drystone.motions import catalogue, processing


def test_study_short_record(tmp_path):
    """4 s of the Kobe record, 2 runs, 3 random sets: every set has finite residuals below
    a physical bound (a block cannot slide farther than the base moves relative to a fixed
    point, |u| <= integral of |v_base|, plus a margin for the rest), the summary and report
    are written, and the random-study fractions are consistent counts."""
    rec = processing.trim(processing.scale_to_pga(catalogue.get("kobe1995"), pga_g=study.KOBE_PGA_G), 3.0, 7.0)
    s = study.run(n_random=3, runs=2, substeps=5, record=rec, workers=2, out=tmp_path, progress=False)
    vb = np.cumsum(rec.acc) * rec.dt
    bound_mm = 1e3 * 2 * np.sum(np.abs(vb)) * rec.dt * tol.STUDY_BOUND_MARGIN  # 2 runs
    for name, res in s["sets"].items():
        r = np.asarray(res["1d"])
        assert r.shape == (2, 5) and np.all(np.isfinite(r))
        assert np.abs(r).max() < bound_mm, name
    rs = s["random_study"]
    assert rs["n_sets"] == 3 and rs["rougher_base"]["n_sets"] + rs["smoother_base"]["n_sets"] == 3
    assert json.loads((tmp_path / "summary.json").read_text())["runs"] == 2
    assert (tmp_path / "report.md").is_file()
    panels = sum(m in s["sets"]["table4_run1"] for m in ("1d", "3d"))  # 3D only where results/ has its runs
    assert_figure(tmp_path / "table4_run1.png", (5.5 * panels, 3.8), dpi=110)  # study.bar_chart


def test_sets_reproducible_and_table4():
    a, b = study.friction_sets(5), study.friction_sets(5)
    assert a == b
    assert a["table4_run2"] == {"mu10": 0.47, "mu20": 0.30, "mu31": 0.50, "mu41": 0.39, "mu42": 0.32, "mu52": 0.35}
    assert all(abs(v - 0.4) <= tol.OGAWA_UNIFORM_SPREAD for v in a["uniform_pm0.02"].values())


def test_experimental_pattern():
    assert study.experimental_pattern([10, 2, 25, 20, 8])
    assert not study.experimental_pattern([30, 2, 25, 20, 8])


def test_experimental_pattern_with_fallen_blocks():
    """A block that fell off (None) counts as moving most; ties at the top are no pattern."""
    from drystone.studies.ogawa.study import experimental_pattern
    assert experimental_pattern([1.0, 0.5, 5.0, 4.0, 2.0])
    assert experimental_pattern([1.0, 0.5, None, None, 2.0])
    assert not experimental_pattern([1.0, 0.5, None, None, None])  # block 5 fell too: no order among them
    assert not experimental_pattern([1.0, 1.0, 5.0, 4.0, 2.0])  # block 2 not the least alone


def test_kobe_pga_is_818_gal_in_g():
    """818 gal = 8.18 m/s^2 = 8.18 / 9.80665 g = 0.834 g (not 0.818 g: gal are cm/s^2, and
    1 g is 980.665 gal, not 1000)."""
    assert study.gal_to_g(980.665) == pytest.approx(1.0, rel=tol.EXACT_REL)
    assert study.KOBE_PGA_G == pytest.approx(8.18 / 9.80665, rel=tol.EXACT_REL)
    assert round(study.KOBE_PGA_G, 3) == 0.834
    rec = study.kobe()
    assert rec.pga_g == pytest.approx(study.KOBE_PGA_G, rel=tol.PGA_READBACK_REL)


@pytest.mark.parametrize("case", ["ogawa_kobe_3d.toml", "ogawa_kobe_3d_once.toml"])
def test_case_files_use_818_gal(case):
    """Every excitation stage of the Ogawa case files is at 818 gal, to within the 5 decimals
    the files carry (1e-5 g = 0.01 gal)."""
    import tomllib
    from drystone import paths
    stages = tomllib.loads((paths.CASES / case).read_text())["stages"]
    pgas = [s["pga_g"] for s in stages if s["type"] == "excitation"]
    assert pgas and all(abs(p - study.KOBE_PGA_G) < tol.CASE_FILE_PGA_G for p in pgas)


def test_sweeps_include_818_gal():
    """The PGA sweep has the record's own level (its runs are the 'reset' runs) and both
    block readings; the cumulative sweep has both readings."""
    import tomllib
    from drystone import paths
    sw = tomllib.loads((paths.CASES / "sweeps" / "ogawa_pga.toml").read_text())["grid"]
    assert any(abs(p - study.KOBE_PGA_G) < tol.SWEEP_PGA_G for p in sw["stages.1.pga_g"])
    assert sorted(sw["case.geometry.orientation"]) == ["flat", "upright"]
    cum = tomllib.loads((paths.CASES / "sweeps" / "ogawa_cumulative.toml").read_text())["grid"]
    assert sorted(cum["case.geometry.orientation"]) == ["flat", "upright"]


def test_overturning_onset_brackets_the_first_level():
    on = study.overturning_onset([{"pga_g": 0.6, "overturned": [3]}, {"pga_g": 0.4, "overturned": []},
                                  {"pga_g": 0.5, "overturned": [4]}, {"pga_g": 0.8, "overturned": [3, 5]}])
    assert (on["onset_pga_g"], on["below_g"], on["monotonic"]) == (0.6, 0.5, True)  # block 4 is not an end block
    on = study.overturning_onset([{"pga_g": 0.4, "overturned": []}, {"pga_g": 0.5, "overturned": []}])
    assert on["onset_pga_g"] is None and on["below_g"] == 0.5
    on = study.overturning_onset([{"pga_g": 0.4, "overturned": [5]}, {"pga_g": 0.5, "overturned": []}])
    assert on["onset_pga_g"] == 0.4 and on["below_g"] is None and not on["monotonic"]


def _fake_3d_run(folder, orientation, pga, n_runs=1, tipped=(), slide_mm=10.0):
    """A finished 3D run folder: every block slid slide_mm x (run number) along x; blocks in
    ``tipped`` rotated 40 deg about y after the last run (past the upright end blocks'
    tipping angle atan(50/100) = 26.6 deg, short of the flat ones' 45 deg)."""
    from drystone.geometry import blockfile as bf
    from drystone.geometry import ogawa_blocks as ob
    folder.mkdir(parents=True)
    bf.write(ob.make(orientation=orientation), folder / "geometry.json")
    ids = np.arange(1, 6)
    t = np.arange(n_runs + 1, dtype=float)
    quat = np.zeros((len(t), 5, 4))
    quat[..., 3] = 1.0
    a = np.radians(40.0)
    for b in tipped:
        quat[-1, b - 1] = [0.0, np.sin(a / 2), 0.0, np.cos(a / 2)]
    np.savez(folder / "histories.npz", t=t, block_ids=ids, quat=quat, quat0=quat[0])
    stages = [{"kind": "gravity"}]
    res = []
    for k in range(1, n_runs + 1):
        stages += [{"kind": "excitation"}, {"kind": "rest"}]
        res.append({"kind": "rest", "sample_time_s": float(k),
                    "displacement_m": {str(b): [1e-3 * slide_mm * k, 0.0, 0.0] for b in ids}})
    (folder / "summary.json").write_text(json.dumps({
        "stage_residuals": res, "inputs": {"stages": stages, "excitations": [{"pga_g": pga, "event": "x"}]}}))


def test_orientation_study_reset_cumulative_and_onset(tmp_path):
    """Synthetic sweeps: the upright end blocks tip over from 0.6 g (onset between 0.5 and
    0.6 g); the same 40 deg does not overturn the squat flat ones (tipping angle 45 deg);
    the 818 gal run is the reset row, the five-run folder the cumulative rows."""
    pga, cum = tmp_path / "pga", tmp_path / "cum"
    for o in ("upright", "flat"):
        for p in (0.5, 0.6, study.KOBE_PGA_G):
            _fake_3d_run(pga / f"{o}_{p}", o, p, tipped=(3,) if p >= 0.6 else ())
        _fake_3d_run(cum / o, o, study.KOBE_PGA_G, n_runs=5)
    st = study.orientation_study(pga, cum)
    up, flat = st["orientations"]["upright"], st["orientations"]["flat"]
    assert (up["onset"]["onset_pga_g"], up["onset"]["below_g"]) == (0.6, 0.5)
    assert flat["onset"]["onset_pga_g"] is None
    assert up["reset"]["overturned"] == [3] and up["reset"]["residual_mm"] == pytest.approx([10.0] * 5)
    assert [r["residual_mm"][0] for r in up["cumulative"]["runs"]] == pytest.approx([10, 20, 30, 40, 50])
    assert any("ASSUMED" in a for a in st["assumed"]["flat"])
    md = "\n".join(study.report_orientation(st, {}))
    assert "| upright (assumed) | 0.5, 0.6, 0.834 |" in md and "between 0.5 and 0.6 g" in md
    assert "none up to 0.834 g" in md and "10.0 (overturned)" in md
    assert "| 3D flat (assumed) | cumulative | 5 | 50.0 |" in md
