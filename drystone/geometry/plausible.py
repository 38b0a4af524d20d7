"""Plausible sizes of dry-stone masonry, to catch a drawing or a scan read in the wrong unit
(a wall drawn in mm read as m is 1000 x too big, a scan in m read as mm 1000 x too small).

A stone's size is the largest extent of its bounding box, the wall's that of all its stones
(platform excluded). Outside ``STONE_SIZE_M`` or ``WALL_SIZE_M`` the geometry is built but a
``warning:`` line on stderr states the size, the range and the unit it was read in. Beyond
``WALL_SIZE_MAX_M`` the geometry is refused: no structure is that large, and the
package's own 0.1 m platform slab would be lost in the round-off of the coordinates
(a 1e20 mm drawing failed as "block 0: vertices are coplanar", blaming the platform).
"""
from __future__ import annotations

import sys

import numpy as np

from .blockfile import GeometryError

#: a masonry unit's largest extent (m): from a 2 cm pinning stone to beyond the largest dressed
#: blocks of Inca walls (Sacsayhuaman's largest, about 9 m long)
STONE_SIZE_M = (0.02, 20.0)
#: a wall's largest extent (m): from a 10 cm laboratory model to a 500 m long terrace wall
WALL_SIZE_M = (0.1, 500.0)
#: refused above (m): 100 km, beyond any structure
WALL_SIZE_MAX_M = 1e5


def _size(points) -> float:
    p = np.asarray(points, float)
    return float(np.max(p.max(axis=0) - p.min(axis=0)))


def check_sizes(stones: dict, where: dict, origin: str, unit: str | None = None, out=None) -> list[str]:
    """Warn (``warning:`` lines on ``out``, default stderr; returned) when the wall made of
    ``stones`` (``{id: (n, 2 or 3) points, m}``) or a stone is outside the plausible sizes;
    refuse (GeometryError naming ``origin``) a wall beyond ``WALL_SIZE_MAX_M``. ``where[id]``
    names a stone, ``unit`` the unit the drawing was read in."""
    allp = np.vstack([np.asarray(p, float) for p in stones.values()])
    wall = _size(allp)
    read = f" (read in {unit})" if unit else ""
    if wall > WALL_SIZE_MAX_M:
        raise GeometryError(f"{origin}: the wall is {wall:.3g} m across{read}, beyond any structure (at most "
                            f"{WALL_SIZE_MAX_M:g} m; masonry walls are {WALL_SIZE_M[0]:g}-{WALL_SIZE_M[1]:g} m): "
                            "check the drawing's units")
    lines = []
    lo, hi = WALL_SIZE_M
    if not lo <= wall <= hi:
        lines.append(f"warning: {origin}: the wall is {wall:.3g} m across{read}, outside the plausible "
                     f"{lo:g}-{hi:g} m for masonry: check the units")
    lo, hi = STONE_SIZE_M
    odd = sorted((bid for bid, p in stones.items() if not lo <= _size(p) <= hi), key=lambda b: _size(stones[b]))
    if odd:
        first = odd[0] if _size(stones[odd[0]]) < lo else odd[-1]
        lines.append(f"warning: {len(odd)} stone(s) outside the plausible {lo:g}-{hi:g} m for a masonry unit"
                     f"{read}, e.g. {where.get(first, f'stone {first}')}: {_size(stones[first]):.3g} m "
                     "across: check the units")
    for line in lines:
        print(line, file=out or sys.stderr)
    return lines
