"""The five-block shaking-table model of Ogawa et al. (Figures 4 and 6, Eqs. 2-3), on a
fixed stone base.

The paper (§3) gives "three blocks of 100x50x100 mm and two blocks of 50x50x100 mm"
without saying which dimension is the height or the depth. Both readings are offered, by
name (``orientation``), and both are ASSUMED (``ASSUMED`` below, copied into the block
file's ``generator`` entry and from there into every run's summary.json):

* ``"upright"`` (the default, used since the first version): the figures read as
  length (x, shaking direction) x thickness (y) x height (z). Blocks 1, 2 and 4 are
  100 mm long, 50 mm thick and 100 mm tall; blocks 3 and 5 are 50 x 50 x 100 mm: slender
  end blocks (height / length = 2) that can overturn.
* ``"flat"``: length x height x depth. Blocks 1, 2, 4 are 100 mm long, 50 mm tall and
  100 mm deep; blocks 3 and 5 are 50 mm long, 50 mm tall and 100 mm deep (squat:
  height / length = 1).

Either way blocks 1 and 2 (a = b = 100 mm along x) stand side by side on the base; on top
block 3 (c = 50 mm) sits on block 1, block 4 (100 mm) spans 50 mm of block 1 and 50 mm of
block 2, block 5 (e = 50 mm) sits on block 2: the layout implied by Eqs. 2-3 (F41 acts on
a - c = 50 mm of block 1, F42 on b - e = 50 mm of block 2). Joints between stacked blocks
take the six friction coefficients mu10, mu20, mu31, mu41, mu42, mu52 (block 0 is the
base); the vertical joints 1-2, 3-4, 4-5 (impacts in the paper's 1D model) take
``mu_vertical``. The paper's 1D model (drystone/studies/ogawa/mrb1d.py) only slides: its friction forces
and masses both scale with thickness x height, so it does not depend on the reading.

Density: the paper gives none; 2600 kg/m^3 (granite) is assumed. A pure-friction response
does not depend on it: gravity, inertia and every friction force scale with the masses, so
the equations of motion divided by the mass are density-free (only the contact
penetrations, W / (K_n A), scale with it). Contact stiffness and damping are not in the
paper either: the Sacsayhuaman paper's FEM calibration (K_n 2e8, K_t 1e8 N/m^3) and light
damping 0.08 (its §3.1 value for small blocks), assumed.
"""
from __future__ import annotations

from . import blockfile as bf
from . import params as pc

A = B = 0.100  # m, lengths of blocks 1 and 2 along x
C = E = 0.050  # m, lengths of blocks 3 and 5
#: orientation -> (thickness y, height of each row z), m
ORIENTATIONS = {"upright": (0.050, 0.100), "flat": (0.100, 0.050)}
DEFAULT_ORIENTATION = "upright"
T, H1 = ORIENTATIONS[DEFAULT_ORIENTATION]  # m, thickness and row height of the default reading
H2 = H1
BASE = (0.40, 0.20, 0.05)  # m, the fixed stone base (top at z = 0)
STACKED = ("mu10", "mu20", "mu31", "mu41", "mu42", "mu52")
PAIRS = {"mu10": (1, 0), "mu20": (2, 0), "mu31": (3, 1), "mu41": (4, 1), "mu42": (4, 2), "mu52": (5, 2)}
END_BLOCKS = (3, 5)  # the top blocks at the two ends of the stack (the ones that can overturn)

#: the two readings of the paper's sizes, in words
READINGS = {
    "upright": "length x thickness x height: blocks 1, 2, 4 100 x 50 x 100 mm, 3 and 5 50 x 50 x 100 mm "
               "(x along the shaking, y thickness, z height)",
    "flat": "length x height x depth: blocks 1, 2, 4 100 mm long, 50 mm tall, 100 mm deep; "
            "3 and 5 50 mm long, 50 mm tall, 100 mm deep",
}
ASSUMED = {k: f"block orientation ASSUMED (paper: '100x50x100 mm', axis order not given): read as {v}"
           for k, v in READINGS.items()}
ASSUMED_COMMON = ["density 2600 kg/m^3 ASSUMED (not in the paper; a sliding response does not depend on it)",
                  "contact stiffness K_n 2e8, K_t 1e8 N/m^3 and damping 0.08 ASSUMED (not in the paper: "
                  "Sacsayhuaman paper's values)",
                  "block layout from Eqs. 2-3 (3 on 1, 4 across 1 and 2, 5 on 2) ASSUMED (Figure 6 not available)"]


def dimensions(orientation: str = DEFAULT_ORIENTATION) -> tuple[float, float]:
    """(thickness along y, height of each row) in m for a named reading of the paper."""
    pc.choice("ogawa_blocks", "orientation", orientation, sorted(ORIENTATIONS))
    return ORIENTATIONS[orientation]


def make(mu10=0.4, mu20=0.4, mu31=0.4, mu41=0.4, mu42=0.4, mu52=0.4, mu_vertical=0.4,
         density=2600.0, kn=2e8, kt=1e8, damping=0.08, orientation=DEFAULT_ORIENTATION) -> dict:
    """The five blocks on the base as a block-file dict (SI units); ``orientation`` is
    ``"upright"`` or ``"flat"`` (module docstring: both are assumed readings)."""
    g = "ogawa_blocks"
    for k, v in dict(mu10=mu10, mu20=mu20, mu31=mu31, mu41=mu41, mu42=mu42, mu52=mu52, mu_vertical=mu_vertical).items():
        pc.number(g, k, v, lo=0)
    pc.material(g, density, kn, kt, damping, mu=0.0)
    t, h = dimensions(orientation)
    x0 = 0.0
    boxes = {
        1: (x0 + A / 2, h / 2, A, h),
        2: (x0 + A + B / 2, h / 2, B, h),
        3: (x0 + C / 2, h + h / 2, C, h),
        4: (x0 + C + (A - C + B - E) / 2, h + h / 2, A - C + B - E, h),
        5: (x0 + A + B - E / 2, h + h / 2, E, h),
    }
    cx = x0 + (A + B) / 2
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((cx, 0.0, -BASE[2] / 2), BASE)}]
    for bid, (x, z, lx, lz) in boxes.items():
        blocks.append({"id": bid, "role": "free", "material": "stone",
                       "vertices": bf.box_vertices((x, 0.0, z), (lx, t, lz))})
    mus = dict(mu10=mu10, mu20=mu20, mu31=mu31, mu41=mu41, mu42=mu42, mu52=mu52)
    joints = [{"blocks": list(PAIRS[k]), "mu": float(v)} for k, v in mus.items()]
    joints += [{"blocks": list(p), "mu": float(mu_vertical)} for p in ((1, 2), (3, 4), (4, 5))]
    params = dict(mus, mu_vertical=mu_vertical, density=density, kn=kn, kt=kt, damping=damping,
                  orientation=orientation, thickness_m=t, row_height_m=h)
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": "ogawa_five_blocks",
            "description": f"Ogawa et al. five-block shaking-table model ({orientation} reading, assumed), "
                           "drystone/geometry/ogawa_blocks.py",
            "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": max(mus.values()),
                                    "damping": damping}},
            "blocks": blocks, "joints": joints,
            "generator": dict(params, name="ogawa_blocks", assumed=[ASSUMED[orientation]] + ASSUMED_COMMON)}
