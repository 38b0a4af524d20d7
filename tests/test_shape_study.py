"""The shape study (issue 25, item 7; drystone/studies/shape/): the bisection of the PGA at
collapse against fake walls with a known collapse PGA, the statistics behind "beyond the
seed-to-seed spread", the walls (same footprint and weight, boundary conditions), the
records' strong-motion windows, and the small plan end to end (YADE)."""
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
from drystone.analyses import bisect as B
from drystone.studies.shape import plan as P
from drystone.studies.shape import study as S


# --- bisection --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("threshold", [0.03, 0.1, 0.1000001, 0.73, 0.8, 1.55, 1.6, 2.41, 3.15, 3.2])
def test_bisection_brackets_a_fake_collapse_pga(threshold):
    """A fake wall that collapses at every PGA >= threshold: the search ends with
    low < threshold <= high, high - low one grid step, in log2(3.2 / 0.1) = 5 runs (6 when
    it lies in the last step, (3.1, 3.2]: the cap is run last, after 3.1 stood), every PGA on
    the grid and run once."""
    b, order = B.search(lambda p: p >= threshold - 1e-12, 0.0, 3.2, 0.1)
    assert b.done and not b.censored and not b.non_monotonic
    assert b.low_g < threshold <= b.high_g + 1e-9
    assert b.high_g - b.low_g == pytest.approx(0.1, abs=B.GRID_TOL)
    assert b.estimate_g == pytest.approx(0.5 * (b.low_g + b.high_g))
    n = 6 if threshold > 3.1 + 1e-9 else 5
    assert len(order) == n == b.runs and len(set(order)) == n
    assert order[0] == 1.6  # the middle first
    assert all(abs(p / 0.1 - round(p / 0.1)) < B.GRID_TOL for p in order)


def test_bisection_censored_when_the_wall_stands_at_the_cap():
    b, order = B.search(lambda p: False, 0.0, 3.2, 0.1)
    assert b.done and b.censored and b.high_g is None and b.low_g == 3.2 and b.estimate_g is None
    assert order == [1.6, 2.4, 2.8, 3.0, 3.1, 3.2]  # the cap is run last: 6 runs
    b, order = B.search(lambda p: p >= 3.2, 0.0, 3.2, 0.1)
    assert (b.low_g, b.high_g, len(order)) == (3.1, 3.2, 6)


def test_bisection_replays_from_observations():
    """The state is the observations: any prefix of a search gives the PGA the search ran
    next, whatever order the observations come in (a resumed study continues the same way)."""
    threshold = 1.27
    _, order = B.search(lambda p: p >= threshold, 0.0, 3.2, 0.1)
    for k in range(len(order)):
        obs = {p: p >= threshold for p in reversed(order[:k])}
        assert B.bracket(obs, 0.0, 3.2, 0.1).next_g == order[k]


def test_bisection_flags_non_monotonic_and_refuses_off_grid():
    b = B.bracket({1.6: True, 0.8: False, 2.4: False, 1.2: False, 1.4: True, 1.3: True}, 0.0, 3.2, 0.1)
    assert b.done and (b.low_g, b.high_g) == (1.2, 1.3) and b.non_monotonic == [2.4]
    with pytest.raises(ValueError, match="not on the 0.1 g grid"):
        B.bracket({0.75: True}, 0.0, 3.2, 0.1)
    with pytest.raises(ValueError, match="outside"):
        B.bracket({3.3: True}, 0.0, 3.2, 0.1)
    with pytest.raises(ValueError, match="above the assumed-safe"):
        B.bracket({}, 1.0, 1.0, 0.1)


def test_small_config_bracket():
    """The small plan: a 1.6 g grid to 3.2 g, 1 or 2 runs per search."""
    c = P.CONFIGS["small"]
    for thr, runs, br in ((1.0, [1.6], (0.0, 1.6)), (2.0, [1.6, 3.2], (1.6, 3.2))):
        b, order = B.search(lambda p: p >= thr, c.pga_low_g, c.pga_cap_g, c.resolution_g)
        assert order == runs and (b.low_g, b.high_g) == br


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
    """The small plan (2 variants, 1 seed, ancash1970 cut to 3 s, a 1.6 g grid): plan, tilt
    sweep, bisection rounds, report, figure (about 1-2 min on 2 cores); run again, every
    run is reused and the report is the same."""
    cfg = replace(P.CONFIGS["small"], results_root=str(outdir / "results"))
    r = S.run(cfg, workers=2)
    assert not r["failed"] and not r["interrupted"] and not r["refused"], r
    assert 1 <= r["rounds"] <= 2
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
            b, order = B.search(lambda p: p >= thr - 1e-9, cfg.pga_low_g, cfg.pga_cap_g, cfg.resolution_g)
            runs = [{"status": "done", "collapsed": p >= thr - 1e-9, "pga_g": p, "name": f"{v}-{s}-{p}",
                     "wall_s": 20.0, "simulated_s": 15.0, "collapsed_stones": [3] if p >= thr else []} for p in order]
            searches.append({"variant": v, "seed": s, "record": "ancash1970", "status": "done",
                             "bracket": b.as_dict(), "runs": runs})
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
    assert m["mean"] == pytest.approx(np.mean([1.8 + 0.1 * s - 0.05 for s in range(3)]), abs=B.GRID_TOL)
    assert_figure(cfg.out_dir / "shape.png", (3.3 * 2 + 0.5, 4.2), 120)
    block = rt.shape(cfg.results)
    assert block.startswith("| measure | (a) coursed |") and "**Answer.**" in block and "\nRuns: " in block
    assert "results/shape/report.md" in block
