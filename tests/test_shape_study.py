"""The shape study (drystone/studies/shape/): the collapse analysis's search on the study's grid
against fake walls with a known collapse PGA, the statistics behind "beyond the seed-to-seed
spread", the walls (same footprint and weight, boundary conditions), the records'
strong-motion windows, and the small plan end to end on the tilt and collapse analyses (YADE)."""
from __future__ import annotations

import csv
import json
from dataclasses import replace
from math import comb

import numpy as np
import pytest

import tolerances as tol
from conftest import assert_figure, requires_yade
from drystone.geometry import blockfile as bf
from drystone.motions.record import Record
from drystone.analyses import ida
from drystone.studies import common as R
from drystone.studies.shape import plan as P
from drystone.studies.shape import study as S


# --- the collapse analysis's search on the study's grid ------------------------------------------------------
def _search(threshold, cap=3.2, res=0.1):
    return ida.search(lambda p: p >= threshold - 1e-12, ida.Params(**R.search_params(cap, res)))


@pytest.mark.parametrize("threshold", [0.03, 0.1, 0.1000001, 0.73, 0.8, 1.55, 1.6, 2.41, 3.15, 3.2])
def test_search_brackets_a_fake_collapse_pga_on_the_grid(threshold):
    """A fake wall that collapses at every PGA >= threshold: the collapse analysis's search
    set to the study's grid (drystone/studies/common.py search_params) ends with low < threshold <= high, high -
    low one grid step, every PGA a point of the 0.1 g grid (the study's bisection grid), run
    once, the first at half the cap: in 5 runs below 1.6 g, 6 above it (the cap is run second
    when the wall stood at 1.6 g)."""
    st, order = _search(threshold)
    assert st.status == "bracketed" and not st.non_monotonic
    assert st.low_g < threshold <= st.high_g + 1e-9
    assert st.high_g - st.low_g == pytest.approx(0.1, abs=1e-9)
    assert order[0] == 1.6 and len(set(order)) == len(order) == (5 if threshold <= 1.6 else 6)
    assert all(abs(p / 0.1 - round(p / 0.1)) < 1e-6 for p in order)


def test_search_censored_when_the_wall_stands_at_the_cap():
    st, order = _search(99.0)
    assert st.status == "censored" and st.high_g is None and st.censored_at_g == 3.2
    assert order == [1.6, 3.2]  # the cap second: a wall standing there is censored after 2 runs


def test_small_config_bracket():
    """The small plan: a 1.6 g grid to 3.2 g, 1 or 2 runs per search."""
    c = P.CONFIGS["small"]
    for thr, runs, br in ((1.0, [1.6], (0.0, 1.6)), (2.0, [1.6, 3.2], (1.6, 3.2))):
        st, order = _search(thr, c.pga_cap_g, c.resolution_g)
        assert order == runs and (st.low_g, st.high_g) == br


def test_tilt_protocol_is_the_tilt_cases():
    """The tilt analysis's keywords read from cases/shape/tilt.toml: its lead-in, rate,
    largest tilt, time after the collapse and direction."""
    assert R.tilt_protocol(P.TILT_CASE) == {"towards": ("+y",), "rate": 1.0, "lead": (5.0, 2.0), "max_deg": 30.0,
                                            "after_collapse": 3.0}


def test_search_state_reads_collapse_json(tmp_path):
    """collapse.json's records as the report reads them: bracketed, censored, pending, failed."""
    runs = [{"pga_g": 1.6, "name": "a-pga_1.6", "status": "done", "collapsed": True, "largest_out_of_plane_m": 0.5}]
    st = R.search_state({"record": "a"}, {"status": "bracketed", "pga_at_collapse_g": [1.5, 1.6], "censored_at_g": None,
                                          "standing_above_collapse_g": [2.4], "runs": runs}, tmp_path)
    assert st["status"] == "done" and st["bracket"]["estimate_g"] == pytest.approx(1.55)
    assert st["bracket"]["non_monotonic"] == [2.4] and st["runs"][0]["max_out_of_plane_mm"] == pytest.approx(500.0)
    st = R.search_state({}, {"status": "censored", "pga_at_collapse_g": None, "censored_at_g": 3.2, "runs": []},
                        tmp_path)
    assert st["bracket"]["censored"] and st["bracket"]["low_g"] == 3.2 and st["bracket"]["estimate_g"] is None
    assert R.search_state({}, None, tmp_path)["status"] == "pending"
    assert R.search_state({}, {"status": "failed", "runs": [], "error": "x", "pga_at_collapse_g": None,
                               "censored_at_g": None}, tmp_path)["status"] == "failed"


# --- statistics -------------------------------------------------------------------------------------------
def test_permutation_test():
    """Exact: two sets of 3 that do not overlap give 2 / C(6, 3) = 0.1 (both directions
    count); identical sets 1; fewer than 2 values per set, no test."""
    assert S.permutation_p([1, 2, 3], [4, 5, 6]) == pytest.approx(2 / comb(6, 3))
    assert S.permutation_p([1, 2, 3], [1, 2, 3]) == 1.0
    assert S.permutation_p([1.0], [2.0, 3.0]) is None
    # 4 vs 4, one value swapped: splits at least as extreme as |mean diff| = 2.5, counted by hand
    a, b = [1, 2, 3, 7], [4, 5, 6, 8]
    pool = a + b
    import itertools
    d0 = abs(np.mean(a) - np.mean(b))
    n = sum(abs(np.mean([pool[i] for i in c]) - np.mean([pool[i] for i in range(8) if i not in c])) >= d0 - 1e-12
            for c in itertools.combinations(range(8), 4))
    assert S.permutation_p(a, b) == pytest.approx(n / comb(8, 4))


def test_answer_from_synthetic_measures():
    """compare/answer on made-up per-seed values: interlocking clearly stronger than the
    rest, the split walls like the convex ones: shape 'yes', splitting beyond the spread."""
    cfg = replace(P.CONFIGS["full"], records=("ancash1970",))
    vals = {"coursed": [1.05, 1.15, 1.25], "polygonal": [1.15, 1.05, 1.35], "interlocking": [2.05, 2.25, 2.15],
            "interlocking_split": [1.25, 1.15, 1.05]}
    ms = {"pga_ancash1970": {"label": "PGA at collapse, ancash1970 (g)", "variants": {
        v: {"seeds": dict(enumerate(x)), **S.describe(x)} for v, x in vals.items()}}}
    cmp = S.compare(ms, cfg)
    rows = {(r["a"], r["b"]): r for r in cmp["pga_ancash1970"]}
    assert rows[("coursed", "polygonal")]["beyond"] is False
    assert rows[("polygonal", "interlocking")]["beyond"] is True
    assert rows[("polygonal", "interlocking")]["difference"] == pytest.approx(np.mean(vals["interlocking"])
                                                                               - np.mean(vals["polygonal"]))
    assert rows[("interlocking", "interlocking_split")]["p"] == pytest.approx(0.1)
    text = " ".join(S.answer(cmp, replace(cfg, tilt=False)))
    assert "shape changes it beyond the seed-to-seed spread: **yes**" in text
    assert "**beyond** the spread" in text and "answer is no (**it changes**)" in text


# --- walls and records ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def walls(tmp_path_factory):
    cfg = replace(P.CONFIGS["full"], seeds=(0,), results_root=str(tmp_path_factory.mktemp("results")))
    return cfg, P.geometries(cfg)


def test_walls_share_footprint_and_weight(walls):
    """Every variant fills the section's 8.64 x 4 m face through 0.8 m: the same weight to
    round-off; (c) has multi-part stones, (c') none and as many blocks as (c) has parts."""
    cfg, g = walls
    fp = P.footprint()
    assert (fp["length"], fp["height"], fp["thickness"]) == pytest.approx((8.64, 4.0, 0.8), abs=tol.EXACT_ABS)
    w = 8.64 * 4.0 * 0.8 * fp["material"]["density"] * 9.80665
    for k, row in g.items():
        assert row["weight_N"] == pytest.approx(w, rel=P.WEIGHT_REL_TOL), k
    assert g["interlocking_s0"]["multi_part"] > 0 and g["polygonal_s0"]["multi_part"] == 0
    assert g["interlocking_split_s0"]["multi_part"] == 0
    assert g["interlocking_split_s0"]["stones"] == g["interlocking_s0"]["parts"]
    assert 35 <= g["polygonal_s0"]["stones"] <= 45  # about the section's 40


def test_walls_boundary_conditions(walls):
    """Stones on the platform fixed, the others free; a free block with a face on either
    end held (blocked_dofs "xYZ"), no other; in (c') per part."""
    cfg, g = walls
    for v in ("polygonal", "interlocking", "interlocking_split"):
        bs = bf.load(g[f"{v}_s0"]["file"])
        for b in bs.blocks:
            if b.role == "platform":
                continue
            pts = b.points
            assert (b.role == "fixed") == bool(pts[:, 2].min() <= 1e-9), (v, b.id)
            at_end = any((np.abs(p[:, 0]) < 1e-6).sum() >= 3 or (np.abs(p[:, 0] - 8.64) < 1e-6).sum() >= 3
                         for p in b.parts)
            assert b.blocked_dofs == ("xYZ" if b.role == "free" and at_end else ""), (v, b.id)


def test_hold_ends_and_fix_bottom_on_a_small_file():
    d = {"blocks": [{"id": 0, "role": "platform", "vertices": [[0, 0, -1], [1, 0, -1], [0, 1, -1], [0, 0, 0]]},
                    {"id": 1, "role": "fixed", "parts": [[[0, 0, 1], [0, 1, 1], [0, 0, 2], [0.5, 0, 1]],
                                                         [[0.5, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, 0, 1]]]},
                    {"id": 2, "role": "free", "vertices": [[0.2, 0, 1], [0.4, 0, 1], [0.2, 1, 1], [0.2, 0, 2]]}]}
    f = P.fix_bottom(d)
    assert [b["role"] for b in f["blocks"]] == ["platform", "fixed", "free"]
    h = P.hold_ends(dict(d, blocks=[dict(b, role="free") if b["id"] == 1 else b for b in d["blocks"]]), 1.0)
    assert h["blocks"][1]["blocked_dofs"] == "xYZ" and "blocked_dofs" not in h["blocks"][2]


def test_strong_motion_window():
    """A quiet record with a burst: the window holds the burst's 5-95 % and the pads, starts
    and ends at zero (taper), keeps the PGA; capped, it is the densest window of that length."""
    dt = 0.01
    t = np.arange(0, 60, dt)
    acc = 0.01 * np.sin(2 * np.pi * t) + np.where((t > 20) & (t < 30), np.sin(2 * np.pi * 2 * t), 0.0)
    acc[np.argmin(np.abs(t - 25.1))] = 3.0
    r = Record(acc, dt)
    w, info = P.strong_motion(r, max_core_s=None)
    assert 19.0 <= info["window_s"][0] < 20.5 and 29.5 < info["window_s"][1] <= 31.0
    assert info["pga_inside"] and w.pga == pytest.approx(3.0)
    assert abs(w.acc[0]) < 1e-12 and abs(w.acc[-1]) < 1e-12
    w, info = P.strong_motion(r, max_core_s=5.0)
    assert info["core_capped_to_s"] == 5.0 and w.duration == pytest.approx(5.0 + 2 * P.PAD_S, abs=dt)
    assert 20.0 - dt <= info["t_arias_s"][0] and info["t_arias_s"][1] <= 30.0 + dt and info["pga_inside"]


# --- end to end -------------------------------------------------------------------------------------------
@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_small_study_end_to_end(outdir):
    """The small plan (2 variants, 1 seed, ancash1970 cut to 1 s, a 1.6 g grid): plan, per
    wall the tilt and collapse analyses, report, figure (about 20 s on 2 cores); run
    again, every run is reused and the report is the same."""
    cfg = replace(P.CONFIGS["small"], results_root=str(outdir / "results"))
    r = S.run(cfg, workers=2)
    assert not r["failed"] and not r["interrupted"] and not r["refused"], r
    assert 1 <= r["rounds"] <= 2
    for v, s in S.walls(cfg):  # each wall's analyses, with their JSON and report
        for a in ("tilt", "collapse"):
            assert (P.wall_dir(cfg, v, s) / a / f"{a}.json").is_file()
            assert (P.wall_dir(cfg, v, s) / a / "report.html").is_file()
    rep = S.report(cfg)
    data = json.loads((cfg.out_dir / "shape.json").read_text())
    assert data["status"]["done"] == 2 and not data["status"]["pending"]
    for st in data["searches"]:
        b = st["bracket"]
        assert b["done"] and [x["pga_g"] for x in st["runs"]][0] == 1.6
        assert b["censored"] or b["high_g"] - b["low_g"] == pytest.approx(1.6)
    for row in data["tilt"]:
        assert row["status"] == "done" and 3.0 < row["collapse_angle_deg"] < 30.0
    rows = list(csv.DictReader(open(cfg.out_dir / "runs.csv")))
    assert len(rows) == 2 + sum(len(st["runs"]) for st in data["searches"])
    assert r["runs_run"] == len(rows)
    text = rep.read_text()
    assert "ASSUMED" in text and "## Cost" in text and "Records shortened" in text
    assert_figure(cfg.out_dir / "shape.png", (3.3 * 2 + 0.5, 4.2), 120)
    again = S.run(cfg, workers=2)
    assert again["runs_run"] == 0 and again["runs_reused"] == len(rows)
    assert S.report(cfg).read_text().split("## Cost")[0] == text.split("## Cost")[0]


# --- report and README block on synthetic runs (no YADE) --------------------------------------------------
def test_report_and_readme_block_on_synthetic_runs(tmp_path, monkeypatch):
    """report.md, shape.json, runs.csv and the figure from made-up searches (collect
    replaced): interlocking walls need 0.8 g more than the others; the README block
    (readme_tables.shape) carries the results table, the answers and the cost line."""
    from drystone.studies import readme_tables as rt

    cfg = replace(P.CONFIGS["full"], records=("ancash1970",), results_root=str(tmp_path / "results"))
    plan = P.build(cfg)
    shift = {"coursed": 0.0, "polygonal": 0.05, "interlocking": 0.8, "interlocking_split": 0.0}
    searches, tilt = [], []
    for v in cfg.variants:
        for s in cfg.seeds:
            thr = 1.0 + shift[v] + 0.1 * s
            b, order = _search(thr - 1e-9, cfg.pga_cap_g, cfg.resolution_g)
            runs = [{"status": "done", "collapsed": p >= thr - 1e-9, "pga_g": p, "name": f"{v}-{s}-{p}",
                     "wall_s": 20.0, "simulated_s": 15.0, "collapsed_stones": [3] if p >= thr else []} for p in order]
            rec = {"status": b.status, "pga_at_collapse_g": b.bracket, "censored_at_g": b.censored_at_g,
                   "standing_above_collapse_g": b.non_monotonic, "runs": runs}
            searches.append(R.search_state({"variant": v, "seed": s, "record": "ancash1970"}, rec, tmp_path))
            tilt.append({"variant": v, "seed": s, "name": f"{v}-s{s}", "status": "done",
                         "collapse_angle_deg": 9.0 + s * 0.2 + (2.0 if v == "interlocking" else 0.0),
                         "reaction_drop_angle_deg": 13.0 + s * 0.1, "first_blocks": [30], "wall_s": 15.0,
                         "simulated_s": 14.0})
    monkeypatch.setattr(S, "collect", lambda c: {"searches": searches, "tilt": tilt, "plan": plan})
    (cfg.out_dir / "timing.json").write_text(json.dumps([{"elapsed_s": 600.0, "rounds": 5}]))
    text = S.report(cfg).read_text()
    assert "**Tilt collapse angle (onset)**: shape changes it beyond the seed-to-seed spread: **yes**" in text
    assert "**PGA at collapse under ancash1970**: shape changes it beyond the seed-to-seed spread: **yes**" in text
    assert "answer is no (**it changes**)" in text  # the split walls behave like the convex ones
    assert f"Runs: {len(tilt) + sum(len(s['runs']) for s in searches)} (12 tilt" in text
    assert "10.0 min" in text and "ASSUMED" in text and "Records shortened" in text
    data = json.loads((cfg.out_dir / "shape.json").read_text())
    m = data["measures"]["pga_ancash1970"]["variants"]["interlocking"]
    # thresholds on the grid (1.8, 1.9, 2.0 g): brackets one step below each, estimates their middles
    assert m["mean"] == pytest.approx(np.mean([1.8 + 0.1 * s - 0.05 for s in range(3)]), abs=1e-9)
    assert_figure(cfg.out_dir / "shape.png", (3.3 * 2 + 0.5, 4.2), 120)
    block = rt.shape(cfg.results)
    assert block.startswith("| measure | (a) coursed |") and "**Answer.**" in block and "\nRuns: " in block
    assert "results/shape/report.md" in block
