"""Sacsayhuaman study (issue 6): Table 3 writer on synthetic results; short white-noise
and record runs of the generated wall end to end through the sweep runner."""
import csv
import json
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure, requires_yade
from drystone import sweep
from drystone.postprocess import compare
from drystone.studies.sacsayhuaman import analysis as an
from drystone.studies.sacsayhuaman import figures as fig


def _res(max_oop_m, stones, collapsed=(), all_collapsed=False, norm_m=None, norm_stones=None, settled=True):
    """A residuals() result (drystone/studies/sacsayhuaman/analysis.py) written by hand."""
    return {"max_out_of_plane_m": max_oop_m, "stones": list(stones), "collapsed": list(collapsed),
            "all_collapsed": all_collapsed, "max_norm_m": max_oop_m if norm_m is None else norm_m,
            "norm_stones": list(stones if norm_stones is None else norm_stones), "settled": settled}


def test_table3_writer_and_layout(tmp_path):
    rows = [an.table3_row("paruro2014", 0.1, _res(5e-4, [35], norm_m=8e-4, norm_stones=[36])),
            an.table3_row("paruro2014", 0.4, _res(2.0, [35], collapsed=[35, 36], settled=False)),
            an.table3_row("cusco2023", 0.1, _res(3e-4, [38, 39], collapsed=list(range(8, 41)), all_collapsed=True,
                                                 settled=None))]
    p = an.write_table3(rows, tmp_path / "table3.csv")
    got = list(csv.DictReader(open(p)))
    assert [r["record"] for r in got] == ["cusco2023", "paruro2014", "paruro2014"]
    assert got[1] == {"record": "paruro2014", "pga_g": "0.1", "max_residual_mm": "0.50", "stones": "35",
                      "collapsed": "false", "max_residual_3d_mm": "0.80", "stones_3d": "36", "settled": "true"}
    assert got[2]["max_residual_mm"] == "" and got[2]["stones"] == "35, 36" and got[2]["collapsed"] == "true"
    assert got[2]["settled"] == "false" and got[0]["settled"] == ""  # not settled / not run to rest
    assert got[0]["stones"] == "all"
    md = an.table3_markdown(rows, compare.paper("sacsayhuaman")["table3"])
    line = next(ln for ln in md.splitlines() if ln.startswith("| 0.1 g"))
    # ours (out of plane, then 3D) beside the paper's, per record, in the paper's column order
    # a collapsed run has no 3D residual either (its stones fall off the platform: a fall height)
    assert line.split(" | ")[1:7] == ["0.5 (35)", "0.8 (36)", "0.5 (35)", "collapse (all)", "-",
                                      "0.3 (38, 39, 40)"]
    line = next(ln for ln in md.splitlines() if ln.startswith("| 0.4 g"))
    assert line.split(" | ")[1] == f"collapse (35, 36) {an.NOT_SETTLED}"
    assert "had not died out" in md  # the mark is explained
    assert "not run" in md  # ancash1970 and the other PGAs


def _fake_run(folder: Path, final: dict, settle: dict | None, summary_collapsed=()) -> Path:
    """A finished run without YADE: four free 1 x 0.8 x 0.8 m stones (0.8 m deep out of plane),
    gravity to 1 s (every stone settles 1 mm), an excitation to 2 s, rest to 3 s; ``final``
    gives each stone's final displacement from its position after gravity (m)."""
    folder.mkdir(parents=True)
    ids = [35, 36, 37, 38]
    x0 = np.array([[2.0 * k, 0.0, 3.6] for k in range(4)])
    box = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.4, 0.4) for z in (-0.4, 0.4)])
    spec = {"name": folder.name,
            "stages": [{"kind": "gravity", "start": 0.0, "end": 1.0, "params": {}},
                       {"kind": "excitation", "start": 1.0, "end": 2.0, "params": {}},
                       {"kind": "rest", "start": 2.0, "end": 3.0, "params": {}}],
            "blocks": [{"id": b, "role": "free", "vertices": (x0[k] + box).tolist()} for k, b in enumerate(ids)]}
    t = np.linspace(0.0, 3.0, 31)
    after_gravity = x0 + [0.0, 0.0, -1e-3]
    pos = np.repeat(x0[None], len(t), axis=0)
    pos[t >= 1.0 - tol.SLACK] = after_gravity
    pos[-1] = after_gravity + np.array([final.get(b, [0.0, 0.0, 0.0]) for b in ids])
    np.savez(folder / "histories.npz", t=t, pos=pos, block_ids=np.array(ids))
    (folder / "spec.json").write_text(json.dumps(spec))
    (folder / "summary.json").write_text(json.dumps(
        {"blocks": {str(b): {"collapsed": b in summary_collapsed} for b in ids}, "run": {"settle": settle}}))
    return folder


def test_residuals_out_of_plane_relative_to_the_base_after_gravity(tmp_path):
    """The paper's quantity is u_y at the end, from the position after gravity (the 1 mm
    settlement is no residual); the 3D norm stays beside it. Stone 36 slid 50 mm along the
    wall (in plane) and 1 mm out of plane: largest in 3D, not out of plane, where 35 (5 mm)
    and 37 (-4.8 mm, within 10 %) are the largest."""
    settle = {"reached": True, "threshold_J": 5e-3, "time_s": 2.6, "final_kinetic_J": 1e-4}
    out = _fake_run(tmp_path / "a", {35: [0.0, 5e-3, -2e-4], 36: [0.05, 1e-3, 0.0], 37: [0.0, -4.8e-3, 0.0],
                                     38: [5e-5, 5e-5, 0.0]}, settle)
    r = an.residuals(out)
    assert r["out_of_plane_m"] == pytest.approx({"35": 5e-3, "36": 1e-3, "37": -4.8e-3, "38": 5e-5}, abs=tol.EXACT_ABS)
    assert r["max_out_of_plane_m"] == pytest.approx(5e-3) and r["stones"] == [35, 37]
    assert r["max_norm_m"] == pytest.approx(np.hypot(0.05, 1e-3)) and r["norm_stones"] == [36]
    assert r["moved"] == [35, 36, 37]  # |u_y| > 0.1 mm
    assert r["collapsed"] == [] and r["settled"] is True and r["end_time_s"] == pytest.approx(3.0)
    row = an.table3_row("ancash1970", 0.2, r)
    assert row["max_residual_mm"] == pytest.approx(5.0) and row["stones"] == "35, 37"
    assert row["max_residual_3d_mm"] == pytest.approx(50.01, abs=tol.LAST_DIGIT_2_DECIMALS) and row["stones_3d"] == "36"


@pytest.mark.parametrize("final, collapsed", [
    ({38: [0.0, 0.41, 0.0]}, [38]),          # slid off its seat: |u_y| > depth / 2 = 0.4 m
    ({38: [0.0, -0.39, -0.05]}, []),         # still over its seat
    ({38: [0.0, 0.3, -0.81]}, [38]),         # fell: lower than it started by more than its height
    ({36: [0.5, 0.0, 0.0]}, []),             # 0.5 m along the wall: not out of the wall
])
def test_collapse_as_the_paper_reads_it(tmp_path, final, collapsed):
    """A stone has collapsed when its centroid has left its seat out of plane (|u_y| > half
    its out-of-plane depth: overturned about its toe or slid off) or it fell; a large move
    in plane is no collapse (summary.json's 3D rule would call it one)."""
    out = _fake_run(tmp_path / "c", final, None, summary_collapsed=[b for b in final if np.linalg.norm(final[b]) > 0.4])
    r = an.residuals(out)
    assert r["collapsed"] == collapsed and r["all_collapsed"] is False and r["settled"] is None
    row = an.table3_row("paruro2014", 0.4, r)
    assert row["collapsed"] is bool(collapsed)
    assert row["max_residual_mm"] is None if collapsed else row["max_residual_mm"] == pytest.approx(
        1e3 * max(abs(v[1]) for v in final.values()))
    if 36 in final:
        assert r["collapsed_summary"] == [36]


def test_unsettled_run_is_said_so(tmp_path):
    settle = {"reached": False, "threshold_J": 5e-3, "time_s": None, "final_kinetic_J": 3.2}
    out = _fake_run(tmp_path / "u", {35: [0.0, 0.1, 0.0]}, settle)
    r = an.residuals(out)
    assert r["settled"] is False and r["settle"]["final_kinetic_J"] == 3.2
    md = an.table3_markdown([an.table3_row("paruro2014", 0.3, r)], compare.paper("sacsayhuaman")["table3"])
    assert f"100.0 (35) {an.NOT_SETTLED}" in md and "had not died out" in md
    from drystone.studies.sacsayhuaman import study
    assert "had not died out" in " ".join(study._unsettled_note([an.table3_row("paruro2014", 0.3, r)]))


def test_resonance_and_settle_overrides_follow_the_record_case():
    """The resonance study runs at the paper's 0.976 Hz and at the wall's own frequency, with
    the rest-until-settled of cases/sacsayhuaman/record.toml (one threshold for every residual)."""
    from drystone.model import case as casemod
    from drystone import paths
    from drystone.studies.sacsayhuaman import study
    assert study.resonance_frequencies(2.0) == {"paper": 0.976, "wall": 2.0}
    assert study.resonance_frequencies(0.9765) == {"paper": 0.976}
    sine = casemod.load(paths.CASES / "sacsayhuaman" / "sine.toml", study.settle_overrides())
    rec = casemod.load(paths.CASES / "sacsayhuaman" / "record.toml")
    assert sine["stages"][1]["start"] == "displacement"  # the paper's Eq. 9 input
    for k in study.SETTLE_KEYS:
        assert sine["stages"][2][k] == rec["stages"][2][k]
    assert rec["stages"][2]["until_kinetic_below_per_weight"] is not None


WALL = {"generator": "sacsayhuaman", "seed": 0}


def short(motion: dict, duration: float) -> dict:
    return {"case": {"geometry": WALL},
            "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2},
                       dict({"type": "excitation", "direction": "y", "duration": duration}, **motion),
                       {"type": "rest", "duration": 0.2}],
            "output": {"interval": 0.005}}


@requires_yade
@pytest.mark.yade
def test_short_white_noise_gives_a_finite_peak_list(outdir):
    """2 s of white noise scaled up (the paper's 0.9 mm peak base displacement spreads its
    energy over 30 s): the spectra of A-D have peaks, all finite and inside the band."""
    from drystone import runner
    c = short({"motion": "white_noise", "seed": 1, "pga_g": 0.02}, 2.0)
    runner.run_dict(c, outdir / "wn.toml", out_dir=outdir / "wn", quiet=True)
    r = an.identification_peaks(outdir / "wn")
    assert set(r["control_points"]) == {"A", "B", "C", "D"}
    for cp in r["control_points"].values():
        assert cp["peaks_hz"] and all(np.isfinite(cp["peaks_hz"]))
        assert all(an.PEAKS["fmin_hz"] <= f <= an.PEAKS["fmax_hz"] for f in cp["peaks_hz"])
    assert_figure(fig.identification(r, compare.paper("sacsayhuaman"), outdir / "id.png"), (9, 4.5), dpi=120)


@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_record_sweep_two_pgas_resumes_and_tabulates(outdir):
    """A short Cusco 2023 window at two PGAs through the sweep runner (local processes):
    residuals grow with the PGA, the second call skips both runs, Table 3 rows and figures
    come out. The Dask backend runs and resumes a sweep in tests/test_sweep.py (the same
    runner, the backend only hands it the runs), so this sweep is not run twice."""
    from drystone import runner
    (outdir / "base.toml").write_text(runner.to_toml(short({"motion": "record", "record": "cusco2023"}, 1.5)))
    p = outdir / "s.toml"
    p.write_text('[sweep]\nname = "rec"\ncase = "base.toml"\n[grid]\n"stages.1.pga_g" = [0.1, 0.8]\n')
    res = sweep.run(p, workers=2, results=outdir / "res")
    assert res["failed"] == []
    res = sweep.run(p, workers=2, results=outdir / "res")
    assert all(r["status"].startswith("skipped") for r in res["runs"].values())
    from drystone.studies.sacsayhuaman import study
    rows = study.table3_rows(Path(res["root"]))
    assert [r["pga_g"] for r in sorted(rows, key=lambda r: r["pga_g"])] == [0.1, 0.8]
    lo, hi = sorted(rows, key=lambda r: r["pga_g"])
    assert lo["record"] == "cusco2023" and not lo["collapsed"]
    assert 0 <= lo["max_residual_mm"] < 50
    assert hi["collapsed"] or hi["max_residual_mm"] > lo["max_residual_mm"]
    s = json.loads((Path(lo["folder"]) / "summary.json").read_text())
    assert s["inputs"]["excitations"][0]["record"] == "cusco2023"  # provenance of the record
    assert_figure(fig.final_states(rows, "pga_g", outdir / "fs.png"), (2 * 5.2, 3.0), dpi=110)  # two panels
    assert_figure(fig.point_a(rows, outdir / "a.png", "cusco2023"), (9, 4), dpi=120)
