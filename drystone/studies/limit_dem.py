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

It writes results/limit_dem/report.md (both tables; ``make docs`` copies them into
docs/beyond-the-papers.md, block ``limit_dem``) and prints it. The DEM is not rerun.
"""
from __future__ import annotations

import re
import statistics
import sys

from drystone import paths
from drystone.analyses import limit as lim
from drystone.geometry import blockfile as bf
from drystone.studies.shape import plan

SEEDS = (0, 1, 2)
#: the tilt-table walls: the groups of the tilt study (name, label, overrides of its case)
TILT_GROUPS = (("constant", "constant section", ["case.geometry.depth_spread=0.0"]),
               ("varying", "stones of varying depth", []))
OUT = paths.RESULTS / "limit_dem"


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


def tilt_limit_angles(overrides, seed: int) -> dict:
    from drystone.studies.tilt import study

    wall = lim.load_wall(study.CASE, [f"case.geometry.seed={seed}"] + list(overrides))
    data, _ = lim.analyse(wall, ["+y"])
    return {fr: e for fr, e in data["directions"]["+y"]["by_friction"].items()}


def _cell(e: dict) -> str:
    return (f"{e['angle_deg']:.2f}" if e["angle_deg"] is not None else "—") + (
        "" if e["status"] == "collapse" else f" ({e['status']})")


def tilt_table(seeds=None, log=print) -> str:
    """Per group and seed; ``seeds`` default: those with published DEM angles."""
    dem = tilt_dem_angles()
    rows = ["| tilt-table wall | seed | limit, associative (deg) | limit, Coulomb (deg) | DEM onset (deg) | "
            "DEM reaction drop (deg) |", "|---|---|---|---|---|---|"]
    for group, label, over in TILT_GROUPS:
        for s in (seeds if seeds is not None else sorted(dem.get(group, {}))):
            e = tilt_limit_angles(over, s)
            log(f"  tilt {group} seed {s}: " + ", ".join(f"{fr} {x['status']} {x['angle_deg']}" for fr, x in e.items()))
            on, drop = dem.get(group, {}).get(s, (None, None))
            f = (lambda x: "not run" if x is None else f"{x:.2f}")
            rows.append(f"| {label} | {s} | {_cell(e['associative'])} | {_cell(e['coulomb'])} | {f(on)} | {f(drop)} |")
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


def report(parts=("tilt", "shape"), log=print) -> str:
    out = ["# The rigid limit angle beside the DEM's tilt angles", "",
           "Limit angles: rigid stones, the geometry as built, towards +y (`python -m drystone.studies.limit_dem`; "
           "drystone/analyses/limit.py). DEM angles: the published runs (not rerun).", ""]
    if "tilt" in parts:
        out += ["## Tilt-table walls", "", tilt_table(log=log), ""]
    if "shape" in parts:
        out += ["## Shape study's walls", "", table(log=log), ""]
    return "\n".join(out)


def main(argv=None) -> int:
    from drystone import atomic

    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.studies.limit_dem", description=__doc__)
    ap.add_argument("--only", nargs="+", choices=("tilt", "shape"), default=["tilt", "shape"],
                    help="which walls (default both: minutes each, the non-associative iteration most of it)")
    a = ap.parse_args(argv)
    text = report(a.only, log=lambda *a: print(*a, file=sys.stderr))
    OUT.mkdir(parents=True, exist_ok=True)
    atomic.write_text(OUT / "report.md", text)
    print(text)
    print(f"written {OUT / 'report.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
