"""The five-block shaking-table model of Ogawa et al. (Figures 4 and 6, Eqs. 2-3), on a
fixed stone base.

Blocks 1 and 2 (a = b = 100 mm along the shaking direction x, thickness t = 50 mm, height
h1 = 100 mm) stand side by side on the base; on top (height h2 = 100 mm) block 3 (c = 50 mm)
sits on block 1, block 4 (100 mm) spans 50 mm of block 1 and 50 mm of block 2, block 5
(e = 50 mm) sits on block 2: the layout implied by Eqs. 2-3 (F41 acts on a - c = 50 mm of
block 1, F42 on b - e = 50 mm of block 2). Joints between stacked blocks take the six
friction coefficients mu10, mu20, mu31, mu41, mu42, mu52 (block 0 is the base); the
vertical joints 1-2, 3-4, 4-5 (impacts in the paper's 1D model) take ``mu_vertical``.

Density: the paper gives none; 2600 kg/m^3 (granite) is assumed. A pure-friction response
does not depend on it: gravity, inertia and every friction force scale with the masses, so
the equations of motion divided by the mass are density-free (only the contact
penetrations, W / (K_n A), scale with it). Contact stiffness and damping are not in the
paper either: the Sacsayhuaman paper's FEM calibration (K_n 2e8, K_t 1e8 N/m^3) and light
damping 0.08 (its §3.1 value for small blocks).
"""
from __future__ import annotations

from . import blockfile as bf

A = B = 0.100  # m, lengths of blocks 1 and 2 along x
C = E = 0.050  # m, lengths of blocks 3 and 5
T = 0.050  # m, thickness (y)
H1 = H2 = 0.100  # m, heights of the two rows
BASE = (0.40, 0.20, 0.05)  # m, the fixed stone base (top at z = 0)
STACKED = ("mu10", "mu20", "mu31", "mu41", "mu42", "mu52")
PAIRS = {"mu10": (1, 0), "mu20": (2, 0), "mu31": (3, 1), "mu41": (4, 1), "mu42": (4, 2), "mu52": (5, 2)}


def make(mu10=0.4, mu20=0.4, mu31=0.4, mu41=0.4, mu42=0.4, mu52=0.4, mu_vertical=0.4,
         density=2600.0, kn=2e8, kt=1e8, damping=0.08) -> dict:
    """The five blocks on the base as a block-file dict (SI units)."""
    x0 = 0.0
    boxes = {
        1: (x0 + A / 2, H1 / 2, A, H1),
        2: (x0 + A + B / 2, H1 / 2, B, H1),
        3: (x0 + C / 2, H1 + H2 / 2, C, H2),
        4: (x0 + C + (A - C + B - E) / 2, H1 + H2 / 2, A - C + B - E, H2),
        5: (x0 + A + B - E / 2, H1 + H2 / 2, E, H2),
    }
    cx = x0 + (A + B) / 2
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((cx, 0.0, -BASE[2] / 2), BASE)}]
    for bid, (x, z, lx, lz) in boxes.items():
        blocks.append({"id": bid, "role": "free", "material": "stone",
                       "vertices": bf.box_vertices((x, 0.0, z), (lx, T, lz))})
    mus = dict(mu10=mu10, mu20=mu20, mu31=mu31, mu41=mu41, mu42=mu42, mu52=mu52)
    joints = [{"blocks": list(PAIRS[k]), "mu": float(v)} for k, v in mus.items()]
    joints += [{"blocks": list(p), "mu": float(mu_vertical)} for p in ((1, 2), (3, 4), (4, 5))]
    params = dict(mus, mu_vertical=mu_vertical, density=density, kn=kn, kt=kt, damping=damping)
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": "ogawa_five_blocks",
            "description": "Ogawa et al. five-block shaking-table model, geometry/ogawa_blocks.py",
            "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": max(mus.values()),
                                    "damping": damping}},
            "blocks": blocks, "joints": joints, "generator": dict(params, name="ogawa_blocks")}
