"""The limit angle beside the DEM's tilt angles for the shipped walls (no YADE, no DEM run).

``python -m drystone.studies.limit_dem`` computes the rigid-block limit tilt angle towards +y
(the studies' tilt direction) with both frictions (drystone/analyses/limit.py), geometry as
built, for

* the tilt-table walls (cases/tilt_wall.toml, the seeds with published DEM angles, stones of varying depth and the
  constant-section walls), beside the tilt study's published DEM onset and reaction-drop
  angles per seed, read from its generated table in docs/validation-sacsayhuaman.md;
* the shape study's four wall variants (drystone/studies/shape/plan.py: coursed, polygonal,
  interlocking, interlocking split) for its seeds, means over the seeds beside the DEM's,
  read from the shape study's generated table in docs/beyond-the-papers.md.

It writes results/limit_dem/report.md (its tables; ``make docs`` copies them into
docs/beyond-the-papers.md, block ``limit_dem``) and prints it. The published DEM runs are not rerun.

**Joint compliance** (``--only compliance``, the one part that runs the DEM): the tilt
analysis (drystone/analyses/tilt.py) of two cheap walls, ``COMPLIANCE_WALLS``, at the case's
K_n and K_t times each of ``K_FACTORS`` (a ``[contact]`` override of every material; the time
step shrinks as 1/sqrt(K_n), so x100 costs ten times x1), beside the rigid limit of the same
wall as built and, for a single toppling stone, the closed form of the compliant joint
(drystone/mechanics/analytic.py ``stone_toppling_tilt_deg``). Each run folder is
results/limit_dem/compliance/<wall>/kn_x<factor>/ (resumable: a finished tilt.json with the
same overrides is read, not rerun).
"""
from __future__ import annotations

import json
import math
import re
import statistics
import sys
from dataclasses import dataclass

from drystone import paths
from drystone.analyses import limit as lim
from drystone.geometry import blockfile as bf
from drystone.studies.shape import plan

SEEDS = (0, 1, 2)
#: the tilt-table walls: the groups of the tilt study (name, label, overrides of its case)
TILT_GROUPS = (("constant", "constant section", ["case.geometry.depth_spread=0.0"]),
               ("varying", "stones of varying depth", []))
OUT = paths.RESULTS / "limit_dem"


@dataclass(frozen=True)
class ComplianceWall:
    """A wall of the joint-compliance runs: its case (relative to the repository), the tilt
    direction, the protocol (a lead-in tilt ``lead`` = (to deg, deg/s), then ``rate`` deg/s
    until collapse, ``after_collapse`` s after the detection), ``overrides`` of the case (a
    shorter settling), and whether the closed form of one toppling stone applies."""
    name: str
    label: str
    case: str
    towards: str
    lead: tuple
    rate: float
    after_collapse: float
    overrides: tuple = ()
    closed_form: bool = False


#: the two cheapest walls that show the effect: one stone (one contact, toppling: the closed
#: form of the compliant joint beside it) and the tilt-table wall of seed 0 (the tilt study's
#: protocol after the lead-in: 2 deg/s to 10 deg, then 1 deg/s; its gravity held 1 s instead of 2 s)
COMPLIANCE_WALLS = (
    ComplianceWall("l_stone", "L-shaped stone, towards -x (toppling)", "cases/examples/l_stone_tilt.toml", "-x",
                   (15.0, 5.0), 0.5, 0.5, closed_form=True),
    ComplianceWall("tilt_wall", "tilt-table wall, seed 0, towards +y", "cases/tilt_wall.toml", "+y",
                   (10.0, 2.0), 1.0, 2.0,
                   ('stages=[{type = "gravity", duration = 1.0, ramp = 0.5}]',)),
)
#: K_n (and K_t) of the case times these
K_FACTORS = (1, 10, 100)


def dem_angles() -> dict:
    """{measure: [cell per variant]} from the shape study's table in docs/beyond-the-papers.md."""
    text = (paths.ROOT / "docs" / "beyond-the-papers.md").read_text()
    block = text.split("<!-- begin:shape -->", 1)[1].split("<!--", 1)[0]
    out = {}
    for line in block.splitlines():
        m = re.match(r"\| tilt collapse angle, (onset|reaction drop) \(deg\) \|(.*)\|\s*$", line)
        if m:
            out[m.group(1)] = [c.strip().split(" (")[0] for c in m.group(2).split("|")]
    return out


def tilt_dem_angles() -> dict:
    """{group: {seed: (onset, reaction drop)}} from the tilt study's table in
    docs/validation-sacsayhuaman.md (its rows name the seeds, then list one angle per seed)."""
    text = (paths.ROOT / "docs" / "validation-sacsayhuaman.md").read_text()
    block = text.split("<!-- begin:tilt -->", 1)[1].split("<!-- end:tilt -->", 1)[0]
    out = {}
    for line in block.splitlines():
        group = "constant" if "constant section" in line and "seeds" in line else \
            "varying" if "varying depth" in line and "seeds" in line else None
        if group is None:
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        seeds = [int(x) for x in re.findall(r"\d+", cells[0].split("seeds", 1)[1])]
        angles = [[float(x) for x in c.split(":")[0].split(",")] for c in cells[1:3]]
        out[group] = {s: (angles[0][k], angles[1][k]) for k, s in enumerate(seeds)}
    return out


def crosscheck_angles(text: str | None = None) -> dict:
    """{seed: {"lmgc90": deg, kn (N/m^3): deg}} of the LMGC90 cross-check's tilt walls (the
    tilt-table wall of varying depth, onset angles: LMGC90's rigid blocks and this package at
    the K_n of each column) from its generated table in docs/beyond-the-papers.md; {} where
    the block has no table."""
    if text is None:
        text = (paths.ROOT / "docs" / "beyond-the-papers.md").read_text()
    if "<!-- begin:crosscheck -->" not in text:
        return {}
    block = text.split("<!-- begin:crosscheck -->", 1)[1].split("<!-- end:crosscheck -->", 1)[0]
    rows = [[c.strip() for c in ln.strip().strip("|").split("|")] for ln in block.splitlines() if ln.startswith("|")]
    if len(rows) < 3 or not rows[0][0].startswith("wall (seed)"):
        return {}
    keys = []
    for h in rows[0][1:]:
        m = re.match(r"package K_n ([0-9.e+-]+)", h)
        keys.append("lmgc90" if h.startswith("LMGC90") else float(m.group(1)) if m else None)
    out = {}
    for r in rows[2:]:
        if not r[0].isdigit():
            continue
        out[int(r[0])] = {k: float(c) for k, c in zip(keys, r[1:]) if k is not None and re.fullmatch(r"-?[0-9.]+", c)}
    return out


def tilt_limit_angles(overrides, seed: int) -> dict:
    from drystone.studies.tilt import study

    wall = lim.load_wall(study.CASE, [f"case.geometry.seed={seed}"] + list(overrides))
    data, _ = lim.analyse(wall, ["+y"])
    return {fr: e for fr, e in data["directions"]["+y"]["by_friction"].items()}


def _cell(e: dict) -> str:
    return (f"{e['angle_deg']:.2f}" if e["angle_deg"] is not None else "—") + (
        "" if e["status"] == "collapse" else f" ({e['status']})")


def tilt_table(seeds=None, log=print) -> str:
    """Per group and seed; ``seeds`` default: those with published DEM angles. Beside the
    limit: the tilt study's DEM angles (K_n 2e8 N/m^3) and, for the walls of varying depth
    (the cross-check's), LMGC90's rigid onset and this package's onset at K_n x 10."""
    dem = tilt_dem_angles()
    xc = crosscheck_angles()
    rows = ["| tilt-table wall | seed | limit, associative (deg) | limit, Coulomb (deg) | DEM onset (deg) | "
            "DEM reaction drop (deg) | DEM onset, K_n × 10 (deg) | LMGC90 onset, rigid (deg) |",
            "|---|---|---|---|---|---|---|---|"]
    f = (lambda x: "not run" if x is None else f"{x:.2f}")
    for group, label, over in TILT_GROUPS:
        for s in (seeds if seeds is not None else sorted(dem.get(group, {}))):
            e = tilt_limit_angles(over, s)
            log(f"  tilt {group} seed {s}: " + ", ".join(f"{fr} {x['status']} {x['angle_deg']}" for fr, x in e.items()))
            on, drop = dem.get(group, {}).get(s, (None, None))
            x = xc.get(s, {}) if group == "varying" else {}
            rows.append(f"| {label} | {s} | {_cell(e['associative'])} | {_cell(e['coulomb'])} | {f(on)} | {f(drop)} | "
                        f"{f(x.get(2e9))} | {f(x.get('lmgc90'))} |")
    return "\n".join(rows)


def limit_angles(variant: str, seed: int) -> dict:
    d = plan.build_variant(variant, seed)
    bs = bf.parse(d, f"shape {variant} seed {seed}", check_overlaps=False)
    mats = {n: {k: getattr(m, k) for k in bf.MATERIAL_PROPERTIES} for n, m in bs.materials.items()}
    wall = lim.wall_of(bs, mats, 9.81, d["name"])
    data, _ = lim.analyse(wall, ["+y"])
    return {fr: e for fr, e in data["directions"]["+y"]["by_friction"].items()}


def table(seeds=SEEDS, log=print) -> str:
    dem = dem_angles()
    rows = ["| variant | limit, associative (deg) | limit, Coulomb (deg) | DEM onset (deg) | DEM reaction drop (deg) |",
            "|---|---|---|---|---|"]
    for k, (variant, (label, _)) in enumerate(plan.VARIANTS.items()):
        per_seed = {}
        for s in seeds:
            per_seed[s] = limit_angles(variant, s)
            for fr, e in per_seed[s].items():
                log(f"  {variant} seed {s} {fr}: {e['status']} {e['angle_deg']}")
        cells = {}
        for fr in lim.FRICTIONS:
            es = {s: per_seed[s][fr] for s in seeds}
            vals = [e["angle_deg"] for e in es.values() if e["angle_deg"] is not None]
            notes = [f"seed {s} {e['status']}" for s, e in es.items() if e["status"] != "collapse"]
            txt = (f"{statistics.mean(vals):.2f}" + (f" ± {statistics.stdev(vals):.2f}" if len(vals) > 1 else "")
                   if vals else "—")
            cells[fr] = txt + (f" ({'; '.join(notes)})" if notes else "")
        rows.append(f"| {label} | {cells['associative']} | {cells['coulomb']} | {dem['onset'][k]} | "
                    f"{dem['reaction drop'][k]} |")
    return "\n".join(rows)


# -- joint compliance: the DEM at K_n x 10, x 100 -------------------------------------------

def base_stiffness(case_path) -> tuple[float, float]:
    """(K_n, K_t) N/m^3 of a case's stones (one value each over its materials, else ValueError)."""
    import tempfile
    from pathlib import Path

    from drystone.model import case as casemod
    from drystone.model import resolve

    case = casemod.load(case_path, [])
    with tempfile.TemporaryDirectory() as tmp:
        bs, _ = resolve._geometry(case, str(case_path), Path(tmp))
    mats = resolve._materials(case, bs, str(case_path))
    kn = {m["kn"] for m in mats.values()}
    kt = {m["kt"] for m in mats.values()}
    if len(kn) != 1 or len(kt) != 1:
        raise ValueError(f"{case_path}: the compliance runs scale one K_n and one K_t, the materials have {kn}, {kt}")
    return kn.pop(), kt.pop()


def stiffness_overrides(kn: float, kt: float, factor: float) -> list[str]:
    return [f"contact.kn={kn * factor:.6g}", f"contact.kt={kt * factor:.6g}"]


def closed_form_deg(wall: lim.Wall, towards: str, kn: float) -> float:
    """The toppling tilt of a single free stone with a flat base on a compliant (Winkler)
    joint of stiffness ``kn`` (analytic.stone_toppling_tilt_deg), its toe the base's
    downhill edge: the check of the compliance runs on one stone."""
    import numpy as np

    from drystone.mechanics import analytic

    free = [b for b in range(len(wall.bodies.ids)) if not wall.bodies.fixed[b]]
    if len(free) != 1:
        raise ValueError(f"{wall.name}: the closed form is for one free stone, it has {len(free)}")
    b = free[0]
    pts = np.vstack(wall.parts[b])
    axis = {"+x": 0, "-x": 0, "+y": 1, "-y": 1}[towards]
    sign = 1.0 if towards.startswith("+") else -1.0
    base = pts[np.isclose(pts[:, 2], pts[:, 2].min(), atol=1e-9)]
    toe = (base[:, axis] * sign).max()
    cen = wall.bodies.centroid[b]
    d = toe - sign * cen[axis]
    e = cen[2] - pts[:, 2].min()
    footprint = float(np.ptp(base[:, axis]))
    width = float(np.ptp(base[:, 1 - axis]))
    return analytic.stone_toppling_tilt_deg(d, e, footprint, width, wall.bodies.mass[b] * wall.gravity, kn)


def compliance_run(w: ComplianceWall, factor: float, log=print) -> dict:
    """One wall's tilt at K_n x ``factor`` (resumable): the direction's entry of its tilt.json
    with ``kn`` (N/m^3), ``factor`` and ``wall_s``."""
    from drystone.analyses import tilt

    case = paths.ROOT / w.case
    kn, kt = base_stiffness(case)
    over = list(w.overrides) + stiffness_overrides(kn, kt, factor)
    out = OUT / "compliance" / w.name / f"kn_x{factor:g}"
    done = out / "tilt.json"
    if done.exists():
        data = json.loads(done.read_text())
        if data.get("overrides") == over and w.towards in data.get("directions", {}):
            return dict(data["directions"][w.towards], kn=kn * factor, factor=factor)
    log(f"  compliance: {w.name} at K_n x {factor:g} ({kn * factor:.3g} N/m^3)")
    data = tilt.tilt(case, [w.towards], out=out, rate=w.rate, lead=w.lead, after_collapse=w.after_collapse,
                     overrides=over, max_deg=45.0, log=log)
    return dict(data["directions"][w.towards], kn=kn * factor, factor=factor)


def compliance_limits(w: ComplianceWall) -> dict:
    """The rigid limit of the wall as built: {"associative", "cone" [lo, hi], "coulomb"} deg
    (None where not a collapse) and the closed form per K_n where it applies (``closed_form``)."""
    wall = lim.load_wall(paths.ROOT / w.case, list(w.overrides))
    out = {}
    for fr in lim.FRICTIONS:
        e, _ = lim.one(wall, w.towards, fr)
        out[fr] = e["angle_deg"] if e["status"] == "collapse" else None
        out[f"{fr}_status"] = e["status"]
        if e.get("cone_bracket"):
            out["cone"] = e["cone_bracket"]["angle_deg"]
    if w.closed_form:
        kn, _ = base_stiffness(paths.ROOT / w.case)
        out["closed_form"] = {f: closed_form_deg(wall, w.towards, kn * f) for f in K_FACTORS}
    return out


def compliance_table(walls, runs: dict, limits: dict) -> str:
    """The markdown table: per wall and K_n factor the DEM's onset and reaction drop (None:
    not run), the rigid limit (associative, the exact cone's bracket, Coulomb) and, where
    given, the closed form of the compliant joint. ``runs``: {wall name: {factor: the tilt
    entry}}; ``limits``: {wall name: compliance_limits}."""
    f2 = (lambda x: "—" if x is None else f"{x:.2f}")
    rows = ["| wall | K_n (N/m^3) | DEM onset (deg) | DEM reaction drop (deg) | closed form, compliant joint (deg) | "
            "rigid limit, associative (deg) [exact cone] | rigid limit, Coulomb (deg) | limit − reaction drop (deg) |",
            "|---|---|---|---|---|---|---|---|"]
    for w in walls:
        L = limits[w.name]
        cone = L.get("cone")
        lim_cell = f2(L["associative"]) + (f" [{f2(cone[0])}–{f2(cone[1])}]" if cone and cone[1] is not None
                                           and abs(cone[1] - cone[0]) > 0.005 else "")
        for f in K_FACTORS:
            r = runs.get(w.name, {}).get(f)
            cf = (L.get("closed_form") or {}).get(f)
            if r is None:
                rows.append(f"| {w.label} | × {f:g} | not run | not run | {f2(cf)} | {lim_cell} | "
                            f"{f2(L['coulomb'])} | — |")
                continue
            drop = r.get("reaction_drop_deg")
            gap = None if drop is None or L["associative"] is None else L["associative"] - drop
            rows.append(f"| {w.label} | {r['kn']:.3g} (× {f:g}) | {f2(r.get('onset_deg'))} | {f2(drop)} | {f2(cf)} | "
                        f"{lim_cell} | {f2(L['coulomb'])} | {f2(gap)} |")
    return "\n".join(rows)


def compliance_protocol(walls=COMPLIANCE_WALLS) -> str:
    """What the compliance table's numbers are and how each was measured."""
    ws = "; ".join(f"{w.label}: `{w.case}`" + (" with " + ", ".join(f"`{o}`" for o in w.overrides) if w.overrides else "")
                   + f", {w.lead[1]:g} deg/s to {w.lead[0]:g} deg, then {w.rate:g} deg/s until collapse"
                   for w in walls)
    return ("DEM: `python -m drystone tilt` (drystone/analyses/tilt.py) of the geometry as built, settled under "
            "gravity, K_n and K_t of every material times the factor (`--set contact.kn=... --set contact.kt=...`); "
            "onset: the tilt at which a stone first moves faster than 5 mm per degree; reaction drop: the moving "
            f"stones' vertical reaction 5 % below their weight. {ws}. Rigid limit: "
            "`python -m drystone limit` of the same wall as built (8-facet pyramid; in brackets the exact cone's "
            "bracket where wider than 0.01 deg); the last column uses the associative limit. Closed form: "
            "one rigid stone rocking on a Winkler joint of the run's K_n (drystone/mechanics/analytic.py "
            "`stone_toppling_tilt_deg`).")


def compliance(walls=COMPLIANCE_WALLS, factors=K_FACTORS, log=print) -> tuple[dict, dict]:
    """Run (or read) every wall at every factor, cheapest first; (runs, limits)."""
    runs, limits = {}, {}
    todo = [(w, f) for w in walls for f in factors]  # the cheapest wall first
    for k, (w, f) in enumerate(todo):
        runs.setdefault(w.name, {})[f] = compliance_run(w, f, log)
        log(f"  compliance {k + 1}/{len(todo)} done: {w.name} x{f:g}: onset "
            f"{runs[w.name][f].get('onset_deg')}, reaction drop {runs[w.name][f].get('reaction_drop_deg')}")
    for w in walls:
        limits[w.name] = compliance_limits(w)
    return runs, limits


#: the report's sections, in order: part -> heading
HEADINGS = {"tilt": "## Tilt-table walls", "shape": "## Shape study's walls",
            "compliance": "## Joint compliance: the DEM at K_n × 10 and × 100"}


def sections(text: str) -> dict:
    """{heading: its text up to the next heading} of a report this study wrote."""
    out, head = {}, None
    for line in text.splitlines():
        if line.startswith("## "):
            head = line
            out[head] = []
        elif head is not None:
            out[head].append(line)
    return {h: "\n".join(b).strip("\n") for h, b in out.items()}


def report(parts=tuple(HEADINGS), log=print, previous: str = "") -> str:
    """The report: the ``parts`` computed now, the others taken from ``previous`` (the report
    written before, when it has them)."""
    old = sections(previous)
    out = ["# The rigid limit angle beside the DEM's tilt angles", "",
           "Limit angles: rigid stones, the geometry as built (`python -m drystone.studies.limit_dem`; "
           "drystone/analyses/limit.py). DEM angles: the published runs (not rerun), except the joint-compliance "
           "runs of the last section, made by this study.", ""]
    for part, head in HEADINGS.items():
        if part in parts:
            if part == "tilt":
                body = tilt_table(log=log)
            elif part == "shape":
                body = table(log=log)
            else:
                runs, limits = compliance(log=log)
                body = compliance_table(COMPLIANCE_WALLS, runs, limits) + "\n\n" + compliance_protocol()
        elif head in old:
            body = old[head]
        else:
            continue
        out += [head, "", body, ""]
    return "\n".join(out)


def main(argv=None) -> int:
    from drystone import atomic

    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.studies.limit_dem", description=__doc__)
    ap.add_argument("--only", nargs="+", choices=tuple(HEADINGS), default=list(HEADINGS),
                    help="which parts to compute, the others kept from the report written before (default all: tilt and shape minutes each, the non-associative iteration most "
                         "of it; compliance runs the DEM, about 30 min the first time on the shared machine, the tilt-table wall at K_n x 100 18 of them, then read back)")
    a = ap.parse_args(argv)
    prev = OUT / "report.md"
    text = report(a.only, log=lambda *a: print(*a, file=sys.stderr),
                  previous=prev.read_text() if prev.exists() else "")
    OUT.mkdir(parents=True, exist_ok=True)
    atomic.write_text(OUT / "report.md", text)
    print(text)
    print(f"written {OUT / 'report.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
