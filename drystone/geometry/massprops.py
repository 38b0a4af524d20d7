"""Mass properties of a stone: the union of its convex parts (one part for a convex stone).

One home for a block's volume (m^3), mass (kg), centroid (m), inertia tensor about the
centroid (kg m^2, global axes) and principal moments and axes, exact: each part's
polyhedral integrals (``polyhedron.moments``: tetrahedra from an inside point), summed over
the parts (the block file refuses parts that overlap by more than ``OVERLAP_TOL``, so the
union's integrals are the sums), the second moments moved to the union's centroid by the
parallel-axis theorem: S = sum_i [S_i + V_i (c_i - c)(c_i - c)^T], I = rho (tr(S) 1 - S).

A single-part stone's volume and centroid are ``polyhedron.volume_centroid``'s bit for bit
(no sum is formed), so convex walls keep their numbers.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import polyhedron as ph


class Moments(NamedTuple):
    """The geometry of a solid, density aside."""
    volume: float  # m^3
    centroid: np.ndarray  # (3,) m
    second: np.ndarray  # (3, 3) m^5: int (x - c)(x - c)^T dV about the centroid


class MassProperties(NamedTuple):
    """A rigid body of uniform density."""
    volume: float  # m^3
    mass: float  # kg
    centroid: np.ndarray  # (3,) m
    inertia: np.ndarray  # (3, 3) kg m^2 about the centroid, global axes
    principal_moments: np.ndarray  # (3,) kg m^2, ascending
    principal_axes: np.ndarray  # (3, 3): column k the unit axis of principal_moments[k]; right-handed


def union_moments(parts, hulls=None) -> Moments:
    """Volume, centroid and second moment about the centroid of the union of convex parts
    (each an (n_i, 3) vertex array, m) that do not overlap. ``hulls``: their hulls, if at
    hand."""
    parts = list(parts)
    hulls = [None] * len(parts) if hulls is None else list(hulls)
    each = [ph.moments(p, h) for p, h in zip(parts, hulls)]
    if len(each) == 1:
        return Moments(*each[0])
    vols = np.array([m[0] for m in each])
    cents = np.array([m[1] for m in each])
    vol = float(vols.sum())
    cent = (vols[:, None] * cents).sum(axis=0) / vol
    second = np.zeros((3, 3))
    for v, c, s in each:
        d = c - cent
        second += s + v * np.outer(d, d)
    return Moments(vol, cent, second)


def inertia(second: np.ndarray, density: float) -> np.ndarray:
    """Inertia tensor (kg m^2) from a second moment S (m^5) and a density (kg/m^3):
    I = rho (tr(S) 1 - S)."""
    s = np.asarray(second, dtype=float)
    return density * (np.trace(s) * np.eye(3) - s)


def principal(inertia_tensor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending, kg m^2) and axes (columns, a right-handed frame)."""
    moments, axes = np.linalg.eigh(np.asarray(inertia_tensor, dtype=float))
    if np.linalg.det(axes) < 0:
        axes[:, 2] = -axes[:, 2]
    return moments, axes


def of_moments(m: Moments, density: float) -> MassProperties:
    """The mass properties of a solid of ``Moments`` ``m`` and uniform ``density`` (kg/m^3)."""
    i = inertia(m.second, density)
    pm, pa = principal(i)
    return MassProperties(m.volume, density * m.volume, m.centroid, i, pm, pa)


def mass_properties(parts, density: float, hulls=None) -> MassProperties:
    """The mass properties of a stone of uniform ``density`` (kg/m^3) made of the convex
    ``parts`` ((n_i, 3) vertex arrays, m; one for a convex stone)."""
    return of_moments(union_moments(parts, hulls), density)
