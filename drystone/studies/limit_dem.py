"""The limit angle beside the DEM's tilt angles for the shape study's walls (no YADE, no run).

``python -m drystone.studies.limit_dem`` builds the shape study's four wall variants
(drystone/studies/shape/plan.py: coursed, polygonal, interlocking, interlocking split) for its
seeds, computes the rigid-block limit tilt angle towards +y (the study's tilt direction) with
both frictions (drystone/analyses/limit.py), and prints a Markdown table of the means over the
seeds beside the DEM's onset and reaction-drop angles, read from the shape study's generated
table in docs/beyond-the-papers.md (the DEM is not rerun). Geometry as built.
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


def main(argv=None) -> int:
    print(table(log=lambda *a: print(*a, file=sys.stderr)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
