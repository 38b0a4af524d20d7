"""The site study (drystone/studies/site/) on the tilt and collapse analyses: the water-level
search (the collapse analysis's search over static runs) against a fake wall, the reversed
records, the walls' sides and the retained case's relation to the free-standing one, the
retained wall's caps against Mononobe-Okabe's limit, the report and its documentation block
from made-up runs, and the small plan end to end (YADE)."""
from __future__ import annotations

import csv
import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from conftest import assert_figure, requires_yade
from drystone.analyses import common, ida
from drystone.model import case as casemod
from drystone.motions import readers
from drystone.studies import common as sc
from drystone.studies.site import plan as P
from drystone.studies.site import report as R
from drystone.studies.site import run as S


def _state(observed: dict, cap: float, res: float, key: dict) -> dict:
    """A search's state as the report reads it, from observations {value: collapsed}."""
    st = ida.step(observed, ida.Params(**sc.search_params(cap, res)))
    rec = {"status": st.status, "pga_at_collapse_g": st.bracket, "censored_at_g": st.censored_at_g,
           "standing_above_collapse_g": st.non_monotonic, "runs": []}
    return sc.search_state(key, rec, Path("/nonexistent"))


def _search(threshold, cap, res):
    return ida.search(lambda x: x >= threshold - 1e-9, ida.Params(**sc.search_params(cap, res)))


# --- the water-level search -------------------------------------------------------------------------------
@pytest.mark.parametrize("threshold", [0.1, 1.3, 2.0, 3.9, 4.0, 9.0])
def test_water_search_on_fake_static_runs(tmp_path, monkeypatch, threshold):
    """The retained wall dry, then the water level at failure (run.static_runs) on a fake wall
    that fails at every level >= threshold (the analyses' run_jobs replaced): the bracket is
    the grid step holding the threshold (censored at the top of the soil when it never fails),
    each static run named by its level and given its water level."""
    seen = []

    def fake(case, runs, root, label, common=(), *a, **k):
        seen.append((label, runs))
        out = {}
        for n, over in runs:
            z = float(over[0].split("=")[1]) if over else 0.0
            out[n] = {"status": "done", "collapsed": bool(over) and z >= threshold - 1e-9, "largest_out_of_plane_m": 0.0}
        return out

    monkeypatch.setattr(common, "run_jobs", fake)
    cfg = replace(P.CONFIGS["small"], results_root=str(tmp_path), level_resolution_m=0.25)
    d = S.static_runs(cfg, log=lambda m: None)
    assert d["dry"]["status"] == "done" and not d["dry"]["collapsed"] and seen[0][0] == "static-dry"
    w = d["water"]
    _, order = _search(threshold, 4.0, 0.25)
    assert [r["level_m"] for r in w["runs"]] == order and order[0] == 2.0
    for r, (label, ((name, over),)) in zip(w["runs"], seen[1:]):
        assert name == r["name"] == f"static-water_{r['level_m']:g}m" and over == [f"loads.soil.water_level={r['level_m']!r}"]
    b = w["bracket"]
    if threshold > 4.0:
        assert b["censored"] and b["low_g"] == 4.0
    else:
        assert b["low_g"] < threshold <= b["high_g"] + 1e-9 and b["high_g"] - b["low_g"] == pytest.approx(0.25)
    assert json.loads((P.static_dir(cfg) / "water.json").read_text())["water"]["bracket"] == b


# --- plan: records, sides, caps ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def small_plan(tmp_path_factory):
    cfg = replace(P.CONFIGS["small"], results_root=str(tmp_path_factory.mktemp("site") / "results"),
                  polarities={"free": ("+",), "retained": ("+", "-")})
    return cfg, P.build(cfg)


def test_reversed_records(small_plan):
    """The reversed window is the window with every sample's sign flipped, exactly, read
    back by the package's record reader (same step, same PGA)."""
    cfg, plan = small_plan
    for name in cfg.records:
        a = readers.read(P.record_file(cfg, name, "+"))
        b = readers.read(P.record_file(cfg, name, "-"))
        assert a.dt == b.dt and a.n == b.n and np.array_equal(b.acc, -a.acc)
        assert "sign reversed" in P.record_file(cfg, name, "-").read_text().splitlines()[5]
        assert plan["records"][name]["reversed"]["file"] == str(P.record_file(cfg, name, "-"))


def test_walls_sides_and_cases():
    """The retained cases are the free-standing ones plus one [[loads]] table (same geometry,
    stages and output); the soil is behind the section's back face (+y, at its largest y),
    the tilts go towards the open side (-y), and the static case's water level is the key
    the study overrides."""
    from drystone.geometry import sacsayhuaman

    free, ret = casemod.load(P.WALLS["free"][1]), casemod.load(P.WALLS["retained"][1])
    assert not free.get("loads") and len(ret["loads"]) == 1
    for k in ("stages", "output"):
        assert free[k] == ret[k]
    assert free["case"]["geometry"] == ret["case"]["geometry"]
    soil = ret["loads"][0]
    wall = sacsayhuaman.make(seed=0)
    y_max = max(np.asarray(b["vertices"])[:, 1].max() for b in wall["blocks"] if b.get("role") != "platform")
    assert soil["into_soil"] == "+y" and soil["back"] == pytest.approx(y_max, abs=1e-9)
    assert soil["delta_deg"] == pytest.approx(2.0 / 3.0 * soil["phi_deg"], rel=1e-15)
    for case in (P.WALLS["free"][2], P.WALLS["retained"][2]):
        tilts = [s for s in casemod.load(case)["stages"] if s["type"] == "tilt"]
        assert tilts and all(s["towards"] == "-y" for s in tilts)
    tilt_free, tilt_ret = casemod.load(P.WALLS["free"][2]), casemod.load(P.WALLS["retained"][2])
    assert tilt_free["stages"] == tilt_ret["stages"] and tilt_ret["loads"][0] == dict(soil)
    static = casemod.load(P.STATIC_CASE, P.static_overrides(1.5))
    assert static["loads"][0]["water_level"] == 1.5
    assert {k: v for k, v in static["loads"][0].items() if k != "water_level"} == \
        {k: v for k, v in soil.items() if k != "water_level"}


def test_searches_are_collapse_analyses_site_only_at_the_surface(small_plan, monkeypatch):
    """Each search is one collapse analysis of its wall's record case under its record file
    (reversed where the polarity is -), the example profile on the excitation stage at the
    surface only, its search on the study's grid up to the search's cap (the analyses' run_jobs
    captured: nothing runs); the search folders differ."""
    cfg, plan = small_plan
    seen = []

    def capture(case, runs, root, label, common_=(), *a, **k):
        seen.append((str(case), runs, list(common_)))
        raise KeyboardInterrupt

    monkeypatch.setattr(common, "run_jobs", capture)
    for wall in ("free", "retained"):
        for site, pol in (("rock", "+"), ("surface", "-" if wall == "retained" else "+")):
            with pytest.raises(KeyboardInterrupt):
                S.collapse_search(cfg, plan, wall, site, "ancash1970", pol, log=lambda m: None)
            case, ((name, own),), over = seen[-1]
            assert case == str(P.record_case(wall).resolve())
            cap = plan["caps"][P.search_id(wall, site, "ancash1970", pol)]["cap_g"]
            assert own[-1] == f"stages.1.pga_g={round(cap / 2, 4)!r}"  # the first run at half the cap
            st = casemod.load(case, over + own)["stages"][1]
            assert Path(st["record"]).resolve() == P.record_file(cfg, "ancash1970", pol).resolve()
            assert (st.get("site") is not None) == (site == "surface")
            if site == "surface":
                assert Path(st["site"]).resolve() == P.PROFILE.resolve()
    dirs = {P.search_dir(cfg, w, s, "ancash1970", p) for w in P.WALLS for s in P.SITES for p in P.POLARITIES}
    assert len(dirs) == 8


def test_retained_caps_keep_mononobe_okabe_solvable(small_plan):
    """Every retained search's cap keeps the motion's largest k_h (towards the soil) below
    tan(phi - beta) x MO_MARGIN; where the cap was lowered, the next grid PGA passes it (the
    run the package would refuse). The free-standing wall keeps the config's cap."""
    cfg, plan = small_plan
    soil = plan["soil"]
    limit = P.MO_MARGIN * math.tan(math.radians(soil["phi_deg"] - soil["beta_deg"]))
    for sid, cap in plan["caps"].items():
        wall, site, rec, pol = sid.split("/")
        if wall == "free":
            assert cap == {"cap_g": cfg.pga_cap_g["free"], "limited_by_mo": False}
            continue
        assert P.max_k_h(cfg, wall, site, rec, pol, cap["cap_g"]) == cap["k_h_at_cap"] < limit
        if cap["limited_by_mo"]:
            assert P.max_k_h(cfg, wall, site, rec, pol, cap["refused_from_g"]) >= limit
    # at rock the scaled record's positive peak is at most the PGA: k_h(p) <= p
    kh = P.max_k_h(cfg, "retained", "rock", "ancash1970", "-", 0.3)
    assert kh == pytest.approx(0.3, rel=1e-12) or kh < 0.3


# --- report on made-up runs (no YADE) ---------------------------------------------------------------------
def test_report_and_docs_block_from_synthetic_runs(small_plan, monkeypatch):
    """report.md, site.json, runs.csv and both figures from made-up searches (collect
    replaced): the comparison and site tables carry the brackets of the searches, the ratio
    of their middles and the cost; the documentation block (readme_tables.site) carries the
    same tables and the run count."""
    from drystone.studies import readme_tables as rt

    cfg, plan = small_plan
    thresholds = {("free", "rock"): 2.0, ("free", "surface"): 1.0, ("retained", "rock"): 0.45,
                  ("retained", "surface"): 0.2}
    searches = []
    for w in plan["walls"]:
        for s in cfg.sites:
            for pol in cfg.polarities[w]:
                cap, res = plan["caps"][P.search_id(w, s, "ancash1970", pol)]["cap_g"], cfg.resolution_g[w]
                thr = thresholds[(w, s)]
                _, order = _search(thr, cap, res)
                runs = [{"status": "done", "collapsed": p >= thr - 1e-9, "pga_g": p, "name": f"{w}-{s}-{pol}-{p}",
                         "wall_s": 30.0, "simulated_s": 10.0, "max_out_of_plane_mm": 12.0,
                         "pga_surface_g": 1.1 * p if s == "surface" else None} for p in order]
                st = _state({p: p >= thr - 1e-9 for p in order}, cap, res,
                            {"wall": w, "site": s, "record": "ancash1970", "polarity": pol, "cap_g": cap,
                             "resolution_g": res})
                searches.append(dict(st, runs=runs))
    _, water_order = _search(2.6, cfg.level_cap_m, cfg.level_resolution_m)
    water_b = _state({z: z >= 2.6 for z in water_order}, cfg.level_cap_m, cfg.level_resolution_m, {})["bracket"]
    data = {"plan": plan, "refused": {}, "searches": searches,
            "tilt": [{"wall": "free", "name": "tilt-free", "status": "done", "collapse_angle_deg": 9.5,
                      "reaction_drop_angle_deg": 13.3, "wall_s": 20.0, "simulated_s": 10.0},
                     {"wall": "retained", "name": "tilt-retained", "status": "done", "collapse_angle_deg": 0.1,
                      "reaction_drop_angle_deg": 4.1, "wall_s": 10.0, "simulated_s": 8.0}],
            "static": {"status": "done", "collapsed": False, "max_out_of_plane_mm": 0.8, "settled": True,
                       "name": "static-dry", "wall_s": 10.0, "simulated_s": 9.0},
            "water": {"status": "done", "bracket": water_b,
                      "runs": [{"status": "done", "collapsed": z >= 2.6, "level_m": z, "wall_s": 10.0,
                                "simulated_s": 9.0, "max_out_of_plane_mm": 1.0} for z in water_order]}}
    monkeypatch.setattr(R, "collect", lambda c: data)
    (cfg.out_dir / "timing.json").write_text(json.dumps([{"elapsed_s": 600.0, "workers": 2}]))
    text = R.write(cfg).read_text()
    table = text.split("## Retained vs free-standing")[1].split("##")[0]
    assert "| PGA at collapse at rock, ancash1970 (g) | (1.6, 3.2] | (0.3, 0.6] |" in table
    assert "| PGA at collapse at rock, ancash1970 reversed (g) | not run | (0.3, 0.6] |" in table
    assert "| water table at static failure (m above the platform) | no soil | (2, 4] m |" in table
    assert "| tilt towards the open side (-y), reaction drop (deg) | 13.30 | 4.10 |" in table
    # free: rock (1.6, 3.2] -> 2.4, surface (0, 1.6] -> 0.8: ratio 1/3; surface PGA at the collapsing 1.6 g run
    assert "| free-standing | ancash1970 | (1.6, 3.2] | (0, 1.6] | 0.33 | 1.76 |" in text
    n_runs = 2 + 1 + len(water_order) + sum(len(s["runs"]) for s in searches)
    assert f"Runs: {n_runs};" in text and "10.0 min on 2 worker(s)" in text
    assert text.count("**ASSUMED**") >= 4
    rows = list(csv.DictReader(open(cfg.out_dir / "runs.csv")))
    assert len(rows) == n_runs
    site_json = json.loads((cfg.out_dir / "site.json").read_text())
    assert site_json["searches"] == searches and site_json["status"]["done"] == len(searches)
    assert_figure(cfg.out_dir / "site.png", (4.2 * 2, 3.8), 110)
    assert_figure(cfg.out_dir / "spectra.png", (3.4 * 2, 3.6), 110)
    block = rt.site(_as_site(cfg))
    assert "| PGA at collapse at rock, ancash1970 (g) | (1.6, 3.2] | (0.3, 0.6] |" in block
    assert "| free-standing | ancash1970 | (1.6, 3.2] | (0, 1.6] | 0.33 | 1.76 |" in block
    assert f"\nRuns: {n_runs};" in block and "results/site/report.md" in block
    check = site_json["hand_check"]  # the retained wall's hand check, in the report and the block
    line = next(ln for ln in text.splitlines() if ln.startswith("Hand check"))
    assert f"tilt of {check['slide_deg']:.2f}°" in line and f"water at {check['slide_m']:.2f} m" in line
    assert line in block


def _as_site(cfg) -> Path:
    """A results folder whose site/report.md is the config's report (readme_tables reads
    results/site/)."""
    root = cfg.results / "as_full"
    (root / "site").mkdir(parents=True, exist_ok=True)
    (root / "site" / "report.md").write_text((cfg.out_dir / "report.md").read_text())
    return root


def test_small_configs_cut_the_rest_and_its_settle_window_and_keep_valid_cases():
    """The small configs' rest (0.5 s, below the cases' 1.5 s settle window) comes with its
    settle window cut to it, so every base case of both studies still loads (the case check
    refuses a window longer than its stage); the full configs change no stage; gravity is the
    quick protocol's."""
    from drystone.studies.shape import plan as shape_plan

    small, full = P.CONFIGS["small"], P.CONFIGS["full"]
    for case, over, k, rest in ((P.record_case("free"), P.common_overrides(small), P.REST_STAGE, small.rest_max_s),
                                (P.record_case("retained"), P.common_overrides(small), P.REST_STAGE, small.rest_max_s),
                                (P.STATIC_CASE, P.static_common(small), P.STATIC_REST_STAGE, 2 * small.rest_max_s),
                                (shape_plan.RECORD_CASE, shape_plan.common_overrides(shape_plan.CONFIGS["small"]),
                                 shape_plan.REST_STAGE, shape_plan.CONFIGS["small"].rest_max_s)):
        base = casemod.load(case)["stages"][k]
        st = casemod.load(case, over)["stages"]
        assert rest < base["settle_window"] and st[k]["duration"] == st[k]["settle_window"] == rest, case
        if case != P.STATIC_CASE:  # the static runs keep the case's gravity
            assert st[0]["duration"] == sc.QUICK_GRAVITY["duration"] and st[0]["ramp"] == sc.QUICK_GRAVITY["ramp"]
    assert P.static_common(full) == [] and not [o for o in P.common_overrides(full) if o.startswith("stages.")]
    assert not [o for o in shape_plan.common_overrides(shape_plan.CONFIGS["full"]) if o.startswith("stages.")]


# --- end to end -------------------------------------------------------------------------------------------
@requires_yade
@pytest.mark.yade
@pytest.mark.slow
def test_small_study_end_to_end(outdir):
    """The small plan (ancash1970 cut to 0.75 s, coarse brackets, both walls, rock and surface,
    tilt, dry and water static runs), every search a collapse analysis: every search ends, the
    report's tables carry what the analyses say (brackets from collapse.json; each run's
    collapse as its folder says, surface PGAs from each run's spec.json), every run is in
    runs.csv; run again, every run is reused (about 40 s on one core)."""
    cfg = replace(P.CONFIGS["small"], results_root=str(outdir / "results"))
    r = S.run(cfg, workers=1)
    assert not r["failed"] and not r["interrupted"] and not r["refused"], r
    text = R.write(cfg).read_text()
    data = json.loads((cfg.out_dir / "site.json").read_text())
    assert data["status"]["pending"] == data["status"]["failed"] == 0
    assert data["status"]["done"] == len(data["searches"]) == 4
    for st in data["searches"]:
        b = st["bracket"]
        assert b["done"] and (b["censored"] or b["high_g"] - b["low_g"] <= st["resolution_g"] + 1e-9)
        for run in st["runs"]:  # each run's collapse and surface PGA as its folder says
            out = P.search_dir(cfg, st["wall"], st["site"], st["record"], st["polarity"]) / "runs" / run["name"]
            assert common.outcome(out)["collapsed"] == run["collapsed"]
            spec = json.loads((out / "spec.json").read_text())
            sites = [e["site"]["pga_surface_g"] for e in spec["excitations"] if e.get("site")]
            assert (sites[0] if sites else None) == run["pga_surface_g"] == S.surface_pga(out)
            assert (st["site"] == "surface") == bool(sites)
    table = text.split("## Retained vs free-standing")[1].split("##")[0]
    for w, label in (("free", "free-standing"), ("retained", "retained (soil behind, ASSUMED)")):
        st = R.find(data, w, "rock", "ancash1970")
        assert R.bracket_text(st) in table
        row = next(ln for ln in text.splitlines() if ln.startswith(f"| {label} | ancash1970 |"))
        assert R.bracket_text(R.find(data, w, "surface", "ancash1970")) in row
    assert data["static"]["status"] == "done" and data["water"]["status"] in ("done", "pending")
    for row in data["tilt"]:
        assert row["status"] == "done" and row["reaction_drop_angle_deg"] is not None
    rows = list(csv.DictReader(open(cfg.out_dir / "runs.csv")))
    assert r["runs_run"] == len(rows)
    assert "ASSUMED" in text and "## Cost" in text
    again = S.run(cfg, workers=1)
    assert again["runs_run"] == 0 and again["runs_reused"] == len(rows)
    assert R.write(cfg).read_text().split("## Cost")[0] == text.split("## Cost")[0]


# --- hand check: the free stones as one rigid body (drystone/studies/site/hand.py) -----------------------
def _box_wall(width=0.8, height=1.0, length=1.0, density=2300.0):
    """One free box stone (``width`` along y, its back face at y = width / 2, the soil on +y)
    on a platform."""
    w2 = width / 2
    box = [[x, y, z] for z in (0.0, height) for x, y in ((0, -w2), (length, -w2), (length, w2), (0, w2))]
    plat = [[x, y, z] for z in (-0.1, 0.0) for x, y in ((-1, -1), (length + 1, -1), (length + 1, 1), (-1, 1))]
    return {"format": "drystone.blocks", "version": 1, "name": "box", "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": 2e8, "kt": 1e8, "mu": 0.5, "damping": 0.8}},
            "blocks": [{"id": 0, "role": "platform", "material": "stone", "vertices": plat},
                       {"id": 1, "role": "free", "material": "stone", "vertices": box}]}


@pytest.mark.parametrize("water", [None, 0.45])
def test_hand_check_is_block_limits_for_a_box(water):
    """For one box stone the hand check's sliding and toppling margins at a tilt theta are
    ep.block_limits' at k_h = sin theta, k_v = 1 - cos theta (the tilted field, as the load
    type reads it): P_h + k_h W - mu((1 - k_v) W + P_v) and overturning - restoring; its
    critical tilt and water level make block_limits' margins zero."""
    import tolerances as tol
    from drystone.mechanics import earth_pressure as ep
    from drystone.studies.site import hand

    width, height, length, rho, mu = 0.8, 1.0, 1.0, 2300.0, 0.5
    soil = ep.EarthPressure(gamma=18e3, phi=math.radians(30), z_top=height, z_base=0.0, into_soil="+y",
                            back=width / 2, delta=math.radians(20), gamma_sat=20e3, water_level=water)
    b = hand.body(_box_wall(width, height, length, rho), soil)

    def closed(theta, s=soil):
        bl = ep.block_limits(width, height, length, rho, s, math.sin(theta), 1.0 - math.cos(theta))
        n = math.cos(theta) * bl.weight + bl.thrust_v
        return bl, bl.thrust_h + bl.inertia - mu * n, bl.overturning - bl.restoring

    for deg in (0.0, 3.0, 8.0, 15.0):
        bl, slide, topple = closed(math.radians(deg))
        assert b.weight == pytest.approx(bl.weight, rel=1e-15)
        got = hand.margins(b, math.radians(deg), mu)
        assert got[0] == pytest.approx(slide, abs=tol.HAND_MARGIN_REL * bl.weight)
        assert got[1] == pytest.approx(topple, abs=tol.HAND_MARGIN_REL * bl.weight * height)
    crit = hand.critical_tilt(b, mu)
    for key, k in (("slide_deg", 1), ("topple_deg", 2)):
        assert 0.0 < crit[key] < 30.0
        assert closed(math.radians(crit[key]))[k] == pytest.approx(0.0, abs=tol.HAND_ROOT_REL * b.weight * height)
    if water is None:  # mu between the dry and the flooded box's: a water table between base and top fails it
        mus = [ep.block_limits(width, height, length, rho, replace_soil(soil, z)).mu_slide for z in (None, height)]
        mu_w = 0.5 * sum(mus)
        z = hand.critical_water(b, mu_w)["slide_m"]
        assert 0.0 < z < height
        assert ep.block_limits(width, height, length, rho, replace_soil(soil, z)).mu_slide == \
            pytest.approx(mu_w, rel=tol.HAND_ROOT_REL)


def replace_soil(soil, z):
    from dataclasses import replace as dc_replace

    return dc_replace(soil, water_level=z)


def test_free_standing_wall_against_the_shape_study(tmp_path):
    """The consistency line compares the free-standing wall's brackets at rock with the shape
    study's coursed wall, seed 0 (results/shape/shape.json), record by record."""
    cfg = replace(P.CONFIGS["full"], results_root=str(tmp_path), records=("ancash1970",))
    b = _state({1.6: False, 3.2: True, 2.4: False, 2.8: False, 3.0: False, 3.1: True}, 3.2, 0.1, {})["bracket"]
    data = {"plan": {"walls": ["free"]}, "searches": [
        {"wall": "free", "site": "rock", "record": "ancash1970", "polarity": "+", "stage": "coarse",
         "status": "done", "bracket": b, "runs": []}]}
    assert R.shape_check(data, cfg) is None  # no shape study
    (tmp_path / "shape").mkdir()
    shape = {"searches": [{"variant": "coursed", "seed": 0, "record": "ancash1970", "status": "done", "bracket": b}]}
    (tmp_path / "shape" / "shape.json").write_text(json.dumps(shape))
    assert R.shape_check(data, cfg).endswith("ancash1970 (3, 3.1] here, (3, 3.1] there: the same brackets.")
    shape["searches"][0]["bracket"] = _state({1.6: False, 2.4: True, 2.0: False, 2.2: True, 2.1: False}, 3.2, 0.1,
                                             {})["bracket"]
    (tmp_path / "shape" / "shape.json").write_text(json.dumps(shape))
    assert R.shape_check(data, cfg).endswith("(2.1, 2.2] there: **they differ**.")
