"""Contact interfaces of a wall as built: the polygons where stones touch face to face (no YADE).

Rigid-block limit analysis (``drystone.mechanics.limit_analysis``) needs, for each pair of
touching stones (or a stone and the platform or a fixed stone), the contact polygon and its
normal. On the wall as built the stones touch exactly (shared faces), where the overlap
kernel (``drystone.mechanics.overlap``) sees no contact at all: touching is not overlapping.
So the interfaces come from the faces: two convex parts of different bodies touch where a
face of one and a face of the other have opposite normals, each face's corners within
``TOL`` of the other's plane, and their polygons overlap (``blockfile.face_patches``: the
same test and clip that decides whether the parts of one stone are joined). A stone of
several convex parts is one body: its parts' patches with a neighbour are all that body's,
and its parts never touch each other.

Candidate pairs: the parts' bounding boxes that touch within ``TOL``
(``blockfile.candidate_pairs``, sort and sweep). Pairs of two fixed bodies carry nothing
the analysis needs and are left out.

Units: metres.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drystone.geometry import blockfile as bf
from drystone.geometry import polyhedron as ph

#: faces within this distance (m) of each other's plane touch (blockfile.OVERLAP_TOL: the
#: tolerance the block files are checked to; a generator's shared corners agree to ~1e-15 m)
TOL = bf.OVERLAP_TOL
#: corners of a patch closer than this (m) to the previous corner are one corner
MERGE = 1e-9


@dataclass
class Interface:
    """One contact polygon: bodies ``a`` and ``b`` (indices), ``normal`` (3,) the unit
    normal from a to b (the outward normal of a's face), ``polygon`` (k, 3) m its corners,
    counter-clockwise about the normal, ``area`` m^2."""
    a: int
    b: int
    normal: np.ndarray
    polygon: np.ndarray
    area: float


def _clean(poly: np.ndarray) -> np.ndarray:
    keep = [0]
    for k in range(1, len(poly)):
        if np.linalg.norm(poly[k] - poly[keep[-1]]) > MERGE:
            keep.append(k)
    if len(keep) > 1 and np.linalg.norm(poly[keep[-1]] - poly[keep[0]]) <= MERGE:
        keep.pop()
    return poly[keep]


def find(parts: list[list[np.ndarray]], fixed, tol: float = TOL, min_area: float = 0.0) -> list[Interface]:
    """The interfaces of bodies given as lists of convex parts (each (n, 3) corners, m);
    ``fixed`` per body (pairs of two fixed bodies are left out); patches of area <=
    ``min_area`` (m^2) or with fewer than 3 distinct corners are left out."""
    owner, verts = [], []
    for b, ps in enumerate(parts):
        for p in ps:
            owner.append(b)
            verts.append(np.asarray(p, float))
    faces = [ph.faces(v) for v in verts]
    lo = np.array([v.min(axis=0) for v in verts])
    hi = np.array([v.max(axis=0) for v in verts])
    out = []
    for i, j in bf.candidate_pairs(lo, hi, -tol):
        a, b = owner[i], owner[j]
        if a == b or (fixed[a] and fixed[b]):
            continue
        for n, poly, area, _ in bf.face_patches(verts[i], faces[i], verts[j], faces[j], tol):
            poly = _clean(poly)
            if len(poly) >= 3 and area > min_area:
                out.append(Interface(a, b, n, poly, area))
    return out
