"""The 40-stone wall section of the Sacsayhuaman paper (§4.1, Figure 19c), generated.

8.64 m long, 4 m high, 0.8 m thick (the external leaf) on a rigid platform. The real
outlines exist only in the paper's figure, so the stones are a seeded irregular polygonal
wall (typology 1: convex stones, irregular joints; drystone/geometry/irregular_wall.py) with the
paper's numbering and roles:

* five courses of 7, 6, 10, 10 and 7 stones;
* numbering: in each course the stones at the wall's two ends come first (left, right),
  then the others left to right, except the top course, numbered left to right: course 1
  = 1-7 (all on the platform, fixed to it), course 2 = 8 (left end), 9 (right end), 10-13,
  course 3 = 14, 15, 16-23, course 4 = 24, 25, 26-33, course 5 = 34 (left end), 35-40;
  so the side blocks are exactly 8, 9, 14, 15, 24, 25 and 34 (40, the top course's right
  end, carries control point D and stays free);
* side blocks may only translate vertically (z) and out of plane (y) and rotate out of
  plane (about x): blocked_dofs "xYZ";
* control points A, B, C, D at the centre of the top faces of blocks 35, 38, 39, 40
  (mid-thickness, z = 4 m).
Material: Table 1, FEM column (2300 kg/m^3, K_n 2e8, K_t 1e8 N/m^3, mu 0.4, damping 0.8).
"""
from __future__ import annotations

import sys

import numpy as np

from . import blockfile as bf
from . import irregular_wall as iw

COURSES = [7, 6, 10, 10, 7]
#: inputs the paper does not state, labelled in every run's geometry.json and summary.json
ASSUMED = ["stone outlines generated (seeded irregular wall), not the paper's: the real outlines exist only in "
           "its Figure 19 (ASSUMED)",
           "course counts 7, 6, 10, 10, 7 (ASSUMED: read from the numbering of Figure 19c, not stated in the text)",
           "stone numbering and side-block positions follow Figure 19c as read (ASSUMED)"]
SIDE_BLOCKS = (8, 9, 14, 15, 24, 25, 34)
CONTROL = {"A": 35, "B": 38, "C": 39, "D": 40}


def _number(course: list[int], k: int) -> list[int]:
    """Order in which the stones of course k (left to right) get the next ids."""
    if k == 0 or k == len(COURSES) - 1:
        return course
    return [course[0], course[-1]] + course[1:-1]


def make(seed=0, irregularity=0.5, density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8) -> dict:
    """The generated 40-stone section as a block-file dict (``seed`` an integer >= 0,
    ``irregularity`` in [0, 1); bad values raise GeometryError)."""
    d = iw.make(length=8.64, height=4.0, thickness=0.8, stones_per_course=COURSES, irregularity=irregularity,
                stagger=0.2, seed=seed, density=density, kn=kn, kt=kt, mu=mu, damping=damping,
                name="sacsayhuaman", _generator="sacsayhuaman")
    platform = d["blocks"][0]
    stones = d["blocks"][1:]
    out, new_id, pos = [platform], 1, 0
    for k, n in enumerate(COURSES):
        course = stones[pos:pos + n]
        pos += n
        for b in _number(course, k):
            b = dict(b, id=new_id)
            if new_id in SIDE_BLOCKS:
                b["blocked_dofs"] = "xYZ"
            out.append(b)
            new_id += 1
    d["blocks"] = out
    cps = []
    for name, bid in CONTROL.items():
        v = np.asarray(next(b for b in out if b["id"] == bid)["vertices"])
        top = v[np.isclose(v[:, 2], v[:, 2].max())]
        cps.append({"name": name, "block": bid, "position": [float(top[:, 0].mean()), 0.0, float(top[:, 2].mean())]})
    d["control_points"] = cps
    d["generator"] = dict(d["generator"], name="sacsayhuaman", seed=seed, assumed=ASSUMED)
    d["description"] = f"Sacsayhuaman 40-stone wall section, generated (seed {seed}): drystone/geometry/sacsayhuaman.py"
    return d


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        raise SystemExit("usage: python -m drystone.geometry.sacsayhuaman OUT.json [SEED]")
    print(bf.write(make(seed=int(sys.argv[2]) if len(sys.argv) == 3 else 0), sys.argv[1]))
