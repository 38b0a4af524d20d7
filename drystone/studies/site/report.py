"""The site study's report from the analyses on disk: ``collect`` reads every search's
collapse.json, the tilt analyses' tilt.json and the static runs' water.json, then ``site.json``, ``runs.csv``,
``site.png`` (PGA at collapse brackets), ``spectra.png`` (the records at rock and at the
surface: 5 %-damped pseudo-acceleration spectra, and the profile's transfer functions),
``report.md`` and ``report.html`` (drystone.postprocess.markdown).

Units: PGAs in g (at rock unless said), levels in m above the platform, angles in degrees,
times in s; spectra in g against the period in s.
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from drystone import atomic
from drystone.postprocess import markdown
from drystone.studies import common as sc
from drystone.studies.site import hand
from drystone.studies.site import plan as planmod
from drystone.studies.site import run as runmod

#: the records' spectra are drawn at this PGA at rock (g), a level the retained wall's
#: searches reach; the surface spectrum depends on it (equivalent-linear site response)
SPECTRA_PGA_G = 0.3
#: spectra: 5 % damping, periods (s)
SPECTRA_DAMPING = 0.05
PERIODS_S = np.geomspace(0.05, 3.0, 60)
CSV_FIELDS = ("kind", "wall", "site", "record", "polarity", "pga_g", "level_m", "name", "status", "collapsed",
              "collapsed_stones", "settled", "max_out_of_plane_mm", "pga_surface_g", "collapse_angle_deg",
              "reaction_drop_angle_deg", "simulated_s", "wall_s", "error")


def collect(config="full") -> dict:
    """Every search, the tilt and static runs, from the analyses' JSON (run.py)."""
    cfg = planmod.get(config)
    plan = planmod.load_plan(cfg)
    refused = sc.read_json(cfg.out_dir / "refused.json") or {}
    walls = [w for w in plan["walls"]]
    out = {"plan": plan, "refused": refused, "searches": [], "tilt": [], "static": None, "water": None}
    for w, site, r, pol in runmod.searches(cfg, walls):
        key = {"wall": w, "site": site, "record": r, "polarity": pol, "stage": "coarse",
               "cap_g": plan["caps"][planmod.search_id(w, site, r, pol)]["cap_g"],
               "resolution_g": planmod.tolerance(cfg, w)}
        if w in refused:
            out["searches"].append(dict(key, status="refused", bracket=None, runs=[], error=refused[w]))
            continue
        d = planmod.search_dir(cfg, w, site, r, pol)
        res = sc.read_json(d / "collapse.json") or {"records": {}}
        st = sc.search_state(key, next(iter(res["records"].values()), None), d)
        for x in st["runs"]:
            x["pga_surface_g"] = runmod.surface_pga(d / "runs" / x["name"])
        out["searches"].append(st)
    if cfg.tilt:
        for w in walls:
            key = {"wall": w, "name": f"tilt-{w}"}
            if w in refused:
                out["tilt"].append(dict(key, status="refused", error=refused[w]))
                continue
            d = planmod.tilt_dir(cfg, w)
            res = sc.read_json(d / "tilt.json") or {"directions": {}}
            direction = next(iter(res["directions"].values()), None)
            row = sc.tilt_row(key, direction, d)
            if row["status"] == "done":  # the onset's time and the tilt's start (``early``)
                run_dir = d / direction["run"]
                s_ = sc.read_json(run_dir / "summary.json") or {}
                spec = sc.read_json(run_dir / "spec.json") or {}
                row.update(onset_time_s=(s_.get("collapse") or {}).get("time_s"),
                           tilt_start_s=next((st["start"] for st in spec.get("stages", []) if st.get("type") == "tilt"),
                                             None))
            out["tilt"].append(row)
    if "retained" in walls and cfg.water and "retained" not in refused:
        data = sc.read_json(planmod.static_dir(cfg) / "water.json") or {}
        out["static"] = data.get("dry") or {"status": "pending", "name": planmod.static_run_name(None)}
        out["water"] = data.get("water") or {"search": "water", "status": "pending", "bracket": None, "runs": []}
    return out


# --- tables -----------------------------------------------------------------------------------------------
def _f(x, spec=".2f", none="-"):
    return none if x is None else format(x, spec)


def bracket_text(st: dict | None, unit: str = "g") -> str:
    """A search's result: (highest standing, lowest collapsing] in ``unit``, '> cap' when it
    stood at the cap, or its state."""
    if not st:
        return "not run"
    b = st.get("bracket")
    if st["status"] != "done" or not b:
        return sc.missing_text(st["status"])
    if b["censored"]:
        return f"> {b['low_g']:g} (stood at the cap)"
    return f"({b['low_g']:g}, {b['high_g']:g}]"


def estimate(st: dict | None) -> float | None:
    """The middle of a finished search's bracket (None while open or censored)."""
    if not st or st["status"] != "done":
        return None
    return st["bracket"].get("estimate_g")


def find(data: dict, wall: str, site: str, record: str, polarity: str = "+") -> dict | None:
    """The search of a wall, site, record and polarity: its finer one where that is done,
    else the coarse one (None if neither)."""
    got = [s for s in data["searches"] if (s["wall"], s["site"], s["record"], s["polarity"])
           == (wall, site, record, polarity)]
    fine = next((s for s in got if s.get("stage") == "refine" and s["status"] == "done"), None)
    return fine or next((s for s in got if s.get("stage", "coarse") == "coarse"), None)


def unique_runs(searches: list) -> list[tuple[dict, dict]]:
    """(search, run) pairs, each run once (a run is named within its search's folder)."""
    seen, out = set(), []
    for s in searches:
        for r in s["runs"]:
            key = (s["wall"], s["site"], s["record"], s["polarity"], r.get("name"))
            if key not in seen:
                seen.add(key)
                out.append((s, r))
    return out


def _runs_text(st: dict, key: str = "pga_g", unit: str = "g") -> str:
    """The runs of a search: value: c (collapsed) or s (standing, with its largest residual
    out of plane in mm), and the surface PGA where there is one."""
    out = []
    for r in st.get("runs", []):
        if r.get("status") != "done":
            out.append(f"{r[key]:g}: {r.get('status')}")
            continue
        s = "c" if r["collapsed"] else f"s {r.get('max_out_of_plane_mm', 0):.0f} mm"
        sp = f" (surface {r['pga_surface_g']:.2f} g)" if r.get("pga_surface_g") is not None else ""
        out.append(f"{r[key]:g}{sp}: {s}")
    return ", ".join(out) or "-"


def early(row: dict | None) -> bool:
    """A tilt run whose onset of motion came before the tilt began (the retained wall's
    stones creep as the soil's load comes on with gravity): its onset angle is no tilt
    angle, the reaction drop is the one to compare."""
    return bool(row and row.get("onset_time_s") is not None and row.get("tilt_start_s") is not None
                and row["onset_time_s"] < row["tilt_start_s"])


def comparison_rows(data: dict, cfg) -> list[list[str]]:
    """Retained vs free-standing, one row per measure: tilt onset and reaction drop, the PGA
    at collapse at rock per record (as recorded; the retained wall reversed too), the water
    level at static failure."""
    walls = data["plan"]["walls"]
    tilt = {r["wall"]: r for r in data["tilt"]}
    rows = []
    if cfg.tilt:
        for key, label in (("collapse_angle_deg", "tilt towards the open side (-y), onset (deg)"),
                           ("reaction_drop_angle_deg", "tilt towards the open side (-y), reaction drop (deg)")):
            rows.append([label] + [_f(tilt.get(w, {}).get(key)) + (" (before the tilt)" if key == "collapse_angle_deg"
                                                                   and early(tilt.get(w)) else "") for w in walls])
    for r in cfg.records:
        for pol in ("+", "-"):
            if not any(pol in cfg.polarities[w] for w in walls):
                continue
            label = f"PGA at collapse at rock, {r}{'' if pol == '+' else ' reversed'} (g)"
            rows.append([label] + [bracket_text(find(data, w, "rock", r, pol)) if pol in cfg.polarities[w]
                                   else "not run" for w in walls])
    if data.get("water") is not None:
        dry = data["static"]
        row = ["water table at static failure (m above the platform)"]
        for w in walls:
            if w != "retained":
                row.append("no soil")
            elif dry.get("status") == "done" and dry["collapsed"]:
                row.append("fails dry")
            else:
                row.append(bracket_text(data["water"]) + " m" if data["water"]["status"] == "done"
                           else bracket_text(data["water"]))
        rows.append(row)
    return rows


def site_rows(data: dict, cfg) -> list[list[str]]:
    """Rock vs surface, one row per wall, record and polarity: the PGA at collapse at rock
    of the record run at rock and propagated to the surface, the ratio of the brackets'
    middles (surface / rock: below 1, the site makes the wall fall at a lower rock PGA), and
    the surface PGA of the lowest collapsing run at the surface."""
    rows = []
    for w in data["plan"]["walls"]:
        for r in cfg.records:
            for pol in cfg.polarities[w]:
                rock, surf = find(data, w, "rock", r, pol), find(data, w, "surface", r, pol)
                e1, e2 = estimate(rock), estimate(surf)
                hi = (surf or {}).get("bracket") or {}
                sp = next((x.get("pga_surface_g") for x in (surf or {}).get("runs", [])
                           if x.get("pga_g") == hi.get("high_g") and x.get("status") == "done"), None)
                rows.append([planmod.WALLS[w][0], r + ("" if pol == "+" else " reversed"), bracket_text(rock),
                             bracket_text(surf), _f(e2 / e1 if e1 and e2 else None), _f(sp)])
    return rows


def _table(head: list[str], rows: list[list[str]]) -> list[str]:
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)] + ["| " + " | ".join(r) + " |" for r in rows]


def shape_check(data: dict, cfg) -> str | None:
    """The free-standing wall at rock against the shape study's coursed wall, seed 0 (the same
    generated section, record windows, stages and collapse reading: results/shape/shape.json),
    record by record; None when that study has not run or this config cuts the records."""
    shape = sc.read_json(cfg.results / "shape" / "shape.json")
    if not shape or cfg.record_duration_s or "free" not in data["plan"]["walls"]:
        return None
    pairs = []
    for r in cfg.records:
        theirs = next((s for s in shape["searches"] if (s["variant"], s["seed"], s["record"]) == ("coursed", 0, r)),
                      None)
        ours = find(data, "free", "rock", r)
        if theirs and ours and theirs["status"] == ours["status"] == "done":
            pairs.append((r, bracket_text(ours), bracket_text(theirs)))
    if not pairs:
        return None
    same = all(a == b for _, a, b in pairs)
    return ("Consistency: the free-standing wall at rock is the shape study's coursed wall, seed 0 (the same "
            "section, record windows, stages and collapse reading; results/shape/report.md): "
            + "; ".join(f"{r} {a} here, {b} there" for r, a, b in pairs)
            + (": the same brackets." if same else ": **they differ**."))


def costs(data: dict) -> dict:
    """Runs, core time (s: each run's wall time, one thread) and simulated time per kind."""
    kinds = {"tilt": [r for r in data["tilt"] if r.get("status") == "done"],
             "static": ([data["static"]] if data.get("static") and data["static"].get("status") == "done" else [])
             + [r for r in (data.get("water") or {}).get("runs", []) if r.get("status") == "done"]}
    for w in data["plan"]["walls"]:
        kinds[f"seismic, {w}"] = [r for s, r in unique_runs(data["searches"]) if s["wall"] == w
                                  and r.get("status") == "done"]
    out = {}
    for k, rows in kinds.items():
        wall = [r["wall_s"] for r in rows if r.get("wall_s")]
        sim = [r["simulated_s"] for r in rows if r.get("simulated_s")]
        out[k] = {"runs": len(rows), "core_s": float(sum(wall)), "simulated_s": float(sum(sim)),
                  "mean_wall_s": float(np.mean(wall)) if wall else None}
    return out


def write_csv(data: dict, path: Path) -> Path:
    rows = [{"kind": "tilt", **r} for r in data["tilt"]]
    if data.get("static"):
        rows.append({"kind": "static", "wall": "retained", **data["static"]})
    rows += [{"kind": "static", "wall": "retained", **r} for r in (data.get("water") or {}).get("runs", [])]
    rows += [{"kind": "seismic", **{k: s[k] for k in ("wall", "site", "record", "polarity")}, **r}
             for s, r in unique_runs(data["searches"])]
    with atomic.aside(path) as _tmp, open(_tmp, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        wr.writeheader()
        for r in rows:
            r = dict(r, collapsed_stones=" ".join(map(str, r.get("collapsed_stones") or [])))
            wr.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in CSV_FIELDS})
    return path


# --- figures ----------------------------------------------------------------------------------------------
def spectra(cfg, pga_g: float = SPECTRA_PGA_G) -> dict:
    """Each record's window (as the runs use it) at ``pga_g`` at rock and at the surface of
    the profile: PGA (g), 5 %-damped Sa (g) at ``PERIODS_S``, and the profile's small-strain
    and strain-compatible transfer functions |H(f)| (drystone.motions.site.propagate, through
    the runner's own motion_for_stage)."""
    from drystone.model import case as casemod
    from drystone.motions import excitation as mex
    from drystone.motions import spectra as msp
    from drystone.units import G_STANDARD

    out = {"pga_rock_g": pga_g, "damping": SPECTRA_DAMPING, "periods_s": PERIODS_S.tolist(), "records": {}}
    for r in cfg.records:
        from drystone.analyses import common

        case = planmod.record_case("free")
        over = planmod.common_overrides(cfg) + planmod.site_overrides("surface")
        d = casemod.load(case, over)
        over += common.record_override(d, planmod.record_file(cfg, r, "+")) + common.pga_override(d, pga_g)
        m = mex.motion_for_stage(casemod.load(case, over)["stages"][planmod.EXCITATION_STAGE])
        row = {}
        for key, rec in (("rock", m.bedrock), ("surface", m.applied)):
            sa = msp.response_spectrum(rec.acc, rec.dt, PERIODS_S, SPECTRA_DAMPING) / G_STANDARD
            row[key] = {"pga_g": float(np.abs(rec.acc).max() / G_STANDARD), "sa_g": sa.tolist()}
        row["site"] = {k: m.site[k] for k in ("f0_linear_hz", "amplification_linear", "f0_compatible_hz",
                                               "amplification_compatible", "iterations", "converged", "tf_freqs_hz",
                                               "tf_linear_abs", "tf_compatible_abs")}
        out["records"][r] = row
    return out


def _save(fig, path: Path, dpi: int = 110) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.savefig(fig, path, dpi=dpi)
    plt.close(fig)
    return path


def spectra_figure(sp: dict, path: Path) -> Path:
    """One panel per record: Sa at rock and at the surface (g) against the period (s); last
    panel: the profile's transfer functions |surface / rock| against the frequency (Hz)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    recs = list(sp["records"])
    fig, axes = plt.subplots(1, len(recs) + 1, figsize=(3.4 * (len(recs) + 1), 3.6))
    T = np.asarray(sp["periods_s"])
    for ax, r in zip(axes, recs):
        d = sp["records"][r]
        for key, c in (("rock", "0.4"), ("surface", "tab:red")):
            ax.plot(T, d[key]["sa_g"], color=c, label=f"{key} (PGA {d[key]['pga_g']:.2f} g)")
        ax.set_xscale("log")
        ax.set_xlabel("period (s)")
        ax.set_ylabel(f"Sa, {100 * sp['damping']:.0f} % damping (g)")
        ax.set_title(f"{r} at {sp['pga_rock_g']:g} g at rock", fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    ax = axes[-1]
    d = sp["records"][recs[0]]["site"]
    f = np.asarray(d["tf_freqs_hz"])
    ax.plot(f, d["tf_linear_abs"], color="k", label=f"small strain (f0 {d['f0_linear_hz']:.2f} Hz)")
    for r in recs:
        s = sp["records"][r]["site"]
        ax.plot(f, s["tf_compatible_abs"], lw=1, label=f"{r}, strain-compatible (f0 {s['f0_compatible_hz']:.2f} Hz)")
    ax.set_xscale("log")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("|surface / rock|")
    ax.set_title("example profile (ASSUMED)", fontsize=9)
    ax.legend(fontsize=6)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def brackets_figure(data: dict, cfg, path: Path) -> Path:
    """One panel per wall: the PGA-at-collapse bracket (at rock, g) of every record and
    polarity, at rock (grey) and at the surface (red); an arrow above the cap where the wall
    stood there."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    walls = data["plan"]["walls"]
    fig, axes = plt.subplots(1, len(walls), figsize=(4.2 * len(walls), 3.8), squeeze=False)
    for ax, w in zip(axes[0], walls):
        labels = []
        for i, (r, pol) in enumerate((r, p) for r in cfg.records for p in cfg.polarities[w]):
            labels.append(r + ("" if pol == "+" else " rev."))
            for dx, site, c in ((-0.12, "rock", "0.4"), (0.12, "surface", "tab:red")):
                st = find(data, w, site, r, pol)
                b = (st or {}).get("bracket")
                if not st or st["status"] != "done" or not b:
                    ax.text(i + dx, 0.02, "·", ha="center")
                elif b["censored"]:
                    ax.annotate("", xy=(i + dx, b["low_g"] * 1.1), xytext=(i + dx, b["low_g"]),
                                arrowprops={"arrowstyle": "->", "color": c})
                else:
                    ax.plot([i + dx] * 2, [b["low_g"], b["high_g"]], color=c, lw=5, solid_capstyle="butt",
                            label=site if i == 0 else None)
        ax.set_xticks(range(len(labels)), labels, rotation=25, ha="right", fontsize=8)
        ax.set_ylabel("PGA at collapse, at rock (g)")
        ax.set_title(f"{planmod.WALLS[w][0]}: rock (grey), surface (red)", fontsize=9)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    return _save(fig, path)


# --- report -----------------------------------------------------------------------------------------------
def write(config="full") -> Path:
    """site.json, runs.csv, the figures and report.md (+ report.html) from the runs on disk."""
    cfg = planmod.get(config)
    data = collect(cfg)
    plan = data["plan"]
    walls = plan["walls"]
    timing = sc.read_json(cfg.out_dir / "timing.json") or []
    sp = spectra(cfg)
    c = costs(data)
    fig_sp = spectra_figure(sp, cfg.out_dir / "spectra.png")
    fig_br = brackets_figure(data, cfg, cfg.out_dir / "site.png")
    write_csv(data, cfg.out_dir / "runs.csv")
    status = {s: sum(st["status"] == s for st in data["searches"]) for s in ("done", "pending", "failed")}
    check = hand.summary() if "retained" in walls else None
    consistency = shape_check(data, cfg)
    atomic.write_text(cfg.out_dir / "site.json", json.dumps(
        {"config": plan["config"], "walls": walls, "refused": data["refused"], "searches": data["searches"],
         "tilt": data["tilt"], "static": data["static"], "water": data["water"], "spectra": sp, "cost": c,
         "timing": timing, "status": status, "hand_check": check}, indent=1, default=str) + "\n")
    soil = plan.get("soil") or {}
    prof = sp["records"][cfg.records[0]]["site"]
    L = [f"# Retained soil and the site (config `{cfg.name}`)", ""]
    if cfg.notes:
        L += [f"**Note: {'; '.join(cfg.notes)}.**", ""]
    if status["pending"] or status["failed"] or data["refused"]:
        L += [f"**Incomplete: {status['done']} of {len(data['searches'])} searches done, {status['pending']} pending, "
              f"{status['failed']} failed; walls not run: {', '.join(data['refused']) or 'none'}.**", ""]
    L += ["## Walls and inputs", "",
          "* **Free-standing**: the generated 40-stone Sacsayhuaman section (cases/site/record.toml; 8.64 m x 0.8 m x "
          "4 m, Table 1's FEM properties, course 1 fixed, side stones held out of the wall's plane), as in the "
          "Sacsayhuaman and shape studies.",
          "* **Retained**: the same case plus one `[[loads]]` table (cases/site/retained_record.toml): the active "
          "earth pressure of soil behind the back face (y = +0.4 m, the soil on +y, the open side -y) over the full "
          "height, Coulomb statically and Mononobe-Okabe under shaking (drystone/model/loads.py, "
          "docs/earth-pressure.md). **ASSUMED soil**"
          + (f": φ = {soil['phi_deg']:g}°, δ = {soil['delta_deg']:.1f}° (2/3 φ), γ = {soil['gamma'] / 1e3:g} kN/m³, "
             f"γ_sat = {(soil.get('gamma_sat') or soil['gamma']) / 1e3:g} kN/m³, level backfill, vertical back, soil "
             f"from z = {soil['z_base']:g} m to {soil['z_top']:g} m, seismic increment {soil['increment']} "
             "(a dense granular fill; sources and reasoning in the case file)" if soil else "")
          + ". The load follows the gravity ramp and the tilt (k_h = sin θ); under shaking k_h = a/g when the "
          "ground accelerates towards the soil (the stones' inertia then points outwards), the static pressure "
          "otherwise. No passive resistance, no soil-structure interaction.",
          f"* **Sites**: at rock, the record as it is; at the surface, the same record scaled to the PGA **at rock** "
          f"and propagated up the example profile (data/site/sacsayhuaman.toml, **ASSUMED**: 50 m of Vs 450 m/s over "
          f"rock of Vs 650 m/s, set to the site's quoted microtremor frequencies and amplification; small-strain f0 "
          f"{prof['f0_linear_hz']:.2f} Hz, |H(f0)| {prof['amplification_linear']:.2f}; pystrata equivalent-linear).",
          "* **Records**: the Sacsayhuaman study's three, the catalogue's **FEMA P695 stand-ins (ASSUMED)**, each cut "
          "to its strong-motion window by the shape study's rule (Arias 5-95 %, at most 18 s, ±1 s Hann pads), out "
          "of plane (y), then a rest of at most 2.5 s"
          + (f"; here cut to {cfg.record_duration_s:g} s and a {cfg.rest_max_s:g} s rest" if cfg.record_duration_s
             else "") + ". `reversed`: the window with its sign reversed (the retained wall's outward half of the "
          "peaks changes with it).", "",
          "| record | source | window (s of the record) | duration run (s) | PGA of the window (g) |",
          "|---|---|---|---|---|"]
    for name in cfg.records:
        r = plan["records"][name]
        fema = r.get("fema")
        src = (f"FEMA P695 {fema['fema_set']} {fema['fema_record_id']}{fema['fema_component']}: {r['event']}, "
               f"{r['station']} (ASSUMED analogue)" if fema else f"user file: {r['event']}")
        dur = min(r["duration_s"], cfg.record_duration_s) if cfg.record_duration_s else r["duration_s"]
        L.append(f"| {name} | {src} | {r['window_s'][0]:.2f}-{r['window_s'][1]:.2f} | {dur:.2f} | {r['pga_g']:.3f} |")
    L += ["", "## Method", "",
          "* Tilt: the platform tilted towards -y, the retained wall's open side (cases/site/tilt.toml, "
          "retained_tilt.toml; 2 deg/s to 5 deg, then 1 deg/s until collapse"
          + (f"; here gravity held {sc.QUICK_GRAVITY['duration']:g} s, {sc.QUICK_TILT['lead_rate']:g} then "
             f"{sc.QUICK_TILT['rate']:g} deg/s" if cfg.quick else "")
          + "): the onset and the reaction drop as the tilt study measures them. Towards the soil is not run: the "
          "load has no passive resistance, so it cannot "
          "represent the soil holding a wall that leans into it. Where the onset of motion came before the tilt began "
          "(\"before the tilt\": the retained wall's stones creep as its soil's load comes on with gravity, and the "
          "onset rule dates the motion there), the reaction drop is the angle to compare.",
          "* PGA at collapse (at rock): the `collapse` analysis (drystone/analyses/collapse.py) per search, its search "
          "set to the study's grid (drystone/studies/common.py `search_params`: the first run at half the cap, the "
          "cap next when the wall stood there, then the middle of the bracket) between 0 g (assumed standing) and a "
          "cap, to a final bracket of "
          + ", ".join(f"{planmod.tolerance(cfg, w):g} g ({w})" for w in walls)
          + "; collapse = the package's one criterion (a stone fell, overturned or left the model: "
          "drystone/analyses/common.py `outcome`). Cap: "
          + ", ".join(f"{cfg.pga_cap_g[w]:g} g ({w})" for w in walls)
          + "; for the retained wall lowered per search below the first grid PGA whose motion would give k_h > "
          "tan(φ − β) at some sample (Mononobe-Okabe has no solution there, and the run is refused): "
          + (", ".join(f"{k} {v['cap_g']:g} g" for k, v in plan["caps"].items() if v.get("limited_by_mo")) or "none "
             "lowered") + "."
          + " ASSUMED: collapse is monotonic in PGA.",
          "* Water table (the 2010 scenario): the load type takes a fixed `water_level`, so the level at which the "
          "retained wall fails statically is found by the same search over static runs (cases/site/retained_static.toml: "
          "gravity and the load ramped over 1 s, then rest up to 8 s until settled), between the dry wall (run "
          f"first, as a check that it stands) and the top of the soil ({cfg.level_cap_m:g} m) on a "
          f"{cfg.level_resolution_m:g} m bracket; failure = a stone collapsed (the same criterion).",
          "* Residuals: each standing run's largest residual out of plane (mm) is listed with the searches; it is "
          "the Table 3 quantity read at the end of the run (after a rest of at most 2.5 s: not always settled).", "",
          "## Retained vs free-standing", "", *_table(["measure"] + [planmod.WALLS[w][0] for w in walls],
                                                     comparison_rows(data, cfg)), "",
          *([f"Hand check (drystone/studies/site/hand.py): the retained wall's free stones as ONE rigid body on its "
             f"base (μ = {check['mu']:g}, weight {check['weight_N'] / 1e3:.0f} kN) under the same soil load slides at a "
             f"tilt of {check['slide_deg']:.2f}° and topples about its front edge at {check['topple_deg']:.2f}°; "
             f"untilted, it slides with the water at {check['slide_m']:.2f} m and topples at {check['topple_m']:.2f} m. "
             "A monolith is not a dry-stone wall (a part of it can go first, its stones can interlock with the held "
             "side stones): an order of magnitude for the runs, not a validation.", ""] if check else []),
          *([consistency, ""] if consistency else []),
          "## At rock and at the surface", "",
          "PGA at collapse **at rock** (g) of each record run at rock and through the example profile; "
          "ratio = the brackets' middles, surface / rock (below 1: the site makes the wall fall at a lower rock PGA); "
          "the surface PGA of the lowest collapsing run at the surface:", "",
          *_table(["wall", "record", "at rock", "at the surface", "ratio", "surface PGA at collapse (g)"],
                  site_rows(data, cfg)), "",
          f"![PGA at collapse]({fig_br.name})", "",
          f"Spectra of the records at {sp['pga_rock_g']:g} g at rock and at the surface (5 % damping), and the "
          "profile's transfer functions:", "",
          "| record | PGA at rock (g) | PGA at the surface (g) | strain-compatible f0 (Hz) | iterations |",
          "|---|---|---|---|---|"]
    for r, d in sp["records"].items():
        L.append(f"| {r} | {d['rock']['pga_g']:.3f} | {d['surface']['pga_g']:.3f} | {d['site']['f0_compatible_hz']:.2f} "
                 f"| {d['site']['iterations']}{'' if d['site']['converged'] else ' (not converged)'} |")
    L += ["", f"![spectra]({fig_sp.name})", "", "## Every search", "",
          *_table(["wall", "site", "record", "search", "bracket at rock (g)", "cap (g)",
                   "runs (PGA at rock: c = collapsed, s = standing with its largest residual)"],
                  [[planmod.WALLS[s["wall"]][0], s["site"], s["record"] + ("" if s["polarity"] == "+" else " reversed"),
                    f"{s.get('stage', 'coarse')}, {s['resolution_g']:g} g", bracket_text(s), f"{s['cap_g']:g}",
                    _runs_text(s)] for s in data["searches"]])]
    odd = [f"{s['wall']} {s['site']} {s['record']}{'' if s['polarity'] == '+' else ' reversed'}: stood at "
           + ", ".join(f"{p:g}" for p in s["bracket"]["non_monotonic"]) + " g"
           for s in data["searches"] if s.get("bracket") and s["bracket"].get("non_monotonic")]
    L += ["", "Non-monotonic searches (standing above a PGA that collapsed the wall): "
          + ("; ".join(odd) if odd else "none among the PGAs run") + "."]
    if data.get("static"):
        d = data["static"]
        L += ["", f"Static, dry: {'collapsed' if d.get('collapsed') else 'standing' if d.get('status') == 'done' else d.get('status')}"
              + (f" (largest residual out of plane {d['max_out_of_plane_mm']:.1f} mm, settled: {d.get('settled')})"
                 if d.get("status") == "done" else "")
              + ". Water-level runs (m: c = failed, s = standing): "
              + (_runs_text(data["water"], "level_m", "m") if data.get("water") else "-") + "."]
    if data["tilt"]:
        L += ["", *_table(["wall", "onset (deg)", "reaction drop (deg)", "first blocks", "wall time (s)"],
                          [[planmod.WALLS[r["wall"]][0], _f(r.get("collapse_angle_deg")),
                            _f(r.get("reaction_drop_angle_deg")), str(r.get("first_blocks") or r.get("status")),
                            _f(r.get("wall_s"), ".0f")] for r in data["tilt"]])]
    if data["refused"]:
        L += ["", "Walls not run (the package refused them before YADE): "
              + "; ".join(f"**{w}**: {why}" for w, why in data["refused"].items()) + "."]
    n_runs = sum(v["runs"] for v in c.values())
    core = sum(v["core_s"] for v in c.values())
    elapsed = sum(t.get("elapsed_s", 0.0) for t in timing)
    loads = [t["load_average_start"][0] for t in timing if t.get("load_average_start")]
    L += ["", "## Cost", "", *_table(["runs", "count", "core-minutes (one thread each)", "simulated (s)",
                                      "mean wall time per run (s)"],
                                     [[k, str(v["runs"]), f"{v['core_s'] / 60:.1f}", f"{v['simulated_s']:.0f}",
                                       _f(v["mean_wall_s"], ".0f")] for k, v in c.items()]), "",
          f"Runs: {n_runs}; {core / 60:.1f} core-minutes of run time; the study's elapsed time over {len(timing)} "
          f"invocation(s) of `run`: {elapsed / 60:.1f} min on {timing[-1].get('workers') if timing else '?'} "
          "worker(s) (including validation, site response, reused runs and post-processing; the machine's other "
          "load included" + (f": load average {', '.join(str(x) for x in loads)} at the start" if loads else "")
          + ").",
          "", "## Assumptions", "",
          "* **ASSUMED**: the records are FEMA P695 far-field stand-ins for the Sacsayhuaman paper's records "
          "(drystone/motions/catalogue.py), cut to their strong-motion windows.",
          "* **ASSUMED**: the site profile (data/site/sacsayhuaman.toml) is set to reproduce the site's quoted "
          "microtremor frequencies and amplification, not measured; equivalent-linear 1-D response, vertical SH waves.",
          "* **ASSUMED**: the retained soil (a dense granular fill, parameters above), over the wall's full height, "
          "a plane Coulomb / Mononobe-Okabe wedge whose k_h follows the base acceleration (no amplification in the "
          "backfill, no passive side, no pore-water inertia or hydrodynamic pressure: docs/earth-pressure.md, "
          "Left out).",
          "* **ASSUMED**: collapse is monotonic in PGA and in the water level (the searches' premise); one "
          "geometry (seed 0), one friction coefficient and stiffness (Table 1's).", ""]
    return markdown.write(cfg.out_dir / "report.md", "\n".join(L) + "\n")
