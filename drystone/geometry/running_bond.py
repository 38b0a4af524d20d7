"""The benchmark wall: 8.64 x 4 x 0.8 m, 5 courses of 8 rectangular blocks in running bond
(the Sacsayhuaman paper's wall section size, §4.1), on a rigid platform, first course fixed.

Odd courses (1, 3, 5): 8 blocks of 1.08 m. Even courses: the joints are offset by half a
block (0.54 m), which with 8 blocks per course means a 0.54 m block at the left end and a
1.62 m block at the right end (0.54 + 6 x 1.08 + 1.62 = 8.64 m). Blocks are numbered
course by course from the bottom, left to right, from 1. Material: the paper's Table 1
FEM column (2300 kg/m^3, K_n 2e8, K_t 1e8 N/m^3, mu 0.4, damping 0.8).
"""
from __future__ import annotations

import sys

from . import blockfile as bf
from . import params as pc

LENGTH, HEIGHT, THICKNESS = 8.64, 4.0, 0.8  # m
COURSES, PER_COURSE = 5, 8
PLATFORM = (10.0, 2.0, 0.2)  # m, top at z = 0


def make(length=LENGTH, height=HEIGHT, thickness=THICKNESS, courses=COURSES, per_course=PER_COURSE,
         density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8) -> dict:
    """The running-bond wall as a block-file dict (SI units): sizes > 0 m, ``courses`` an
    integer >= 1, ``per_course`` an integer >= 2 (even courses have a half and a 1.5 block)."""
    g = "running_bond"
    for k, v in (("length", length), ("height", height), ("thickness", thickness)):
        pc.positive(g, k, v, "m")
    pc.integer(g, "courses", courses, lo=1)
    pc.integer(g, "per_course", per_course, lo=2)
    pc.material(g, density, kn, kt, damping, mu=mu)
    unit = length / per_course
    ch = height / courses
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((length / 2, 0.0, -PLATFORM[2] / 2), PLATFORM)}]
    bid = 1
    for c in range(courses):
        if c % 2 == 0:
            widths = [unit] * per_course
        else:
            widths = [unit / 2] + [unit] * (per_course - 2) + [1.5 * unit]
        x = 0.0
        for w in widths:
            blocks.append({"id": bid, "role": "fixed" if c == 0 else "free", "material": "stone",
                           "vertices": bf.box_vertices((x + w / 2, 0.0, (c + 0.5) * ch), (w, thickness, ch))})
            x += w
            bid += 1
    params = {"length": length, "height": height, "thickness": thickness, "courses": courses,
              "per_course": per_course, "density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": "running_bond",
            "description": "40-block running-bond wall (benchmark), drystone/geometry/running_bond.py",
            "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
            "blocks": blocks, "generator": dict(params, name="running_bond")}


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit("usage: python -m drystone.geometry.running_bond OUT.json")
    print(bf.write(make(), sys.argv[1]))
