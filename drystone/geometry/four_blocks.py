"""The four-block verification model of the Sacsayhuaman paper (§3.1, Figures 6-9).

Blocks 0.220 x 0.105 x 0.050 m at 2200 kg/m^3 (24.93 N each); K_n = 1.96e7 N/m^3,
K_t = 0.82e7 N/m^3, friction angle 38 deg, damping 0.08 (paper §3.1). Blocks 3 and 4 are
fixed side by side, block 1 lies on 3 and 4, block 2 on block 1.

Figure 6 is not available, so the layout is ours (docs/assumed-inputs.md and docs/validation-sacsayhuaman.md): blocks 3
and 4 stand on end (0.050 along x, 0.105 along y, 0.220 high, tops at z = 0) with no gap
between them; block 1 lies flat across both with its centre of mass over block 3
(x = -0.025 m), block 2 flat on block 1. When block 3 settles by s, block 1 pivots on the
top edge of block 4 (x = 0) and rests on the far top edge of block 3 (x = -0.05 m), so its
tilt is atan(s / 0.05 m): 45 deg at s = 50 mm, past the 38 deg at which block 2 must slip
(reached at s = 0.05 tan 38 deg = 39.1 mm). Lying blocks 3 and 4 flat instead (0.22 m
long along x) would give at most atan(0.05 / 0.11) = 24 deg: no slip at all. Block 1's
centre sits 10 mm left of the pivot (X_BLOCK1), so that the centre of mass of blocks 1 and
2 stays between the two support edges up to 45 deg (it is 7.6 mm inside at 45 deg).

Block 1 rests on two edges, so its supports push perpendicular to its face, like block 1
pushes block 2: with the same friction everywhere, blocks 1 and 2 reach their friction
limit at the same tilt and slide off the supports together (we ran it: the stack slides
down the edges and topples at about 17 mm of settlement). The supports are therefore
rough, restrained blocks: joints 1-3 and 1-4 have mu = SUPPORT_MU = 1.0 (45 deg), which
isolates the joint under test, 1-2, with the paper's 38 deg.
"""
from __future__ import annotations

import math

from . import blockfile as bf
from . import params as pc

L, W, H = 0.220, 0.105, 0.050  # block length (x), width (y), height (z), m
PIVOT_LEVER = 0.050  # m, distance from block 4's edge to block 3's far edge
X_BLOCK1 = -0.003  # m, centre of blocks 1 and 2, just left of the pivot (over block 3)
SUPPORT_MU = 1.0  # friction of the support joints 1-3 and 1-4 (see above)
#: inputs the paper does not give, labelled in every run's geometry.json and summary.json
ASSUMED = ["four-block layout ASSUMED (the paper's Figure 6 is not available): blocks 3 and 4 on end, block 1 "
           f"across them with its centre {abs(X_BLOCK1) * 1e3:.0f} mm over block 3, block 2 on block 1",
           f"support joints 1-3 and 1-4 rough, mu = {SUPPORT_MU} (ASSUMED, to isolate the joint under test 1-2)"]


def make(density=2200.0, kn=1.96e7, kt=0.82e7, friction_angle_deg=38.0, damping=0.08) -> dict:
    """The four-block model as a block-file dict (paper §3.1 values by default)."""
    pc.material("four_blocks", density, kn, kt, damping, friction_angle_deg=friction_angle_deg)
    stand = (PIVOT_LEVER, W, L)  # blocks 3 and 4 on end
    blocks = [
        {"id": 1, "role": "free", "material": "stone",
         "vertices": bf.box_vertices((X_BLOCK1, 0.0, H / 2), (L, W, H))},
        {"id": 2, "role": "free", "material": "stone",
         "vertices": bf.box_vertices((X_BLOCK1, 0.0, 1.5 * H), (L, W, H))},
        {"id": 3, "role": "fixed", "material": "stone",
         "vertices": bf.box_vertices((-PIVOT_LEVER / 2, 0.0, -L / 2), stand)},
        {"id": 4, "role": "fixed", "material": "stone",
         "vertices": bf.box_vertices((PIVOT_LEVER / 2, 0.0, -L / 2), stand)},
    ]
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": "four_blocks",
            "description": "Sacsayhuaman paper §3.1 four-block model; layout: drystone/geometry/four_blocks.py",
            "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt,
                                    "friction_angle_deg": friction_angle_deg, "damping": damping}},
            "blocks": blocks,
            "joints": [{"blocks": [1, 3], "mu": SUPPORT_MU}, {"blocks": [1, 4], "mu": SUPPORT_MU}],
            "generator": {"name": "four_blocks", "density": density, "kn": kn, "kt": kt,
                          "friction_angle_deg": friction_angle_deg, "damping": damping, "assumed": ASSUMED}}


def tilt_for_settlement(s: float) -> float:
    """Rigid-body tilt of block 1 (deg) for a settlement s (m) of block 3."""
    return math.degrees(math.atan2(s, PIVOT_LEVER))
