"""Earth pressure of the retained soil on the back faces of the stones (no YADE).

The static active pressure is Coulomb's and its seismic increment Mononobe-Okabe's, pseudo-static
(Kramer 1996, *Geotechnical Earthquake Engineering*, §11.3.2 eq. 11.5-11.6 and §11.6.1
eq. 11.12-11.14; Das, *Principles of Foundation Engineering*, "Coulomb's active pressure"):

    K_A  = cos^2(phi - alpha) /
           { cos^2(alpha) cos(delta + alpha)
             [1 + sqrt( sin(delta + phi) sin(phi - beta) / (cos(delta + alpha) cos(beta - alpha)) )]^2 }
    K_AE = cos^2(phi - alpha - theta) /
           { cos(theta) cos^2(alpha) cos(delta + alpha + theta)
             [1 + sqrt( sin(delta + phi) sin(phi - beta - theta)
                        / (cos(delta + alpha + theta) cos(beta - alpha)) )]^2 },
    theta = atan(k_h / (1 - k_v)),   P_A = 1/2 K_A gamma H^2,   P_AE = 1/2 K_AE gamma H^2 (1 - k_v)

(K_AE at k_h = k_v = 0 is K_A; alpha = beta = delta = 0 gives Rankine's tan^2(45 deg - phi/2)).
Angles, all in rad here (degrees only at the case-file boundary): ``phi`` the soil's friction
angle, ``delta`` the wall friction (the thrust is inclined by delta from the face normal, its
tangential part pointing down the face: in the active state the soil settles against the wall),
``beta`` the backfill slope (rising away from the wall), ``alpha`` the batter of the back face from
the vertical, positive when the face leans over the soil side (the soil lies on the face, as in
Das's Coulomb figure; a wall that leans back into the hill has alpha < 0). ``k_h`` is positive when
the inertia of the soil wedge points towards the wall (the ground accelerates towards the soil),
``k_v`` positive when the wedge's vertical inertia points up (the ground accelerates downwards).
Mononobe-Okabe has no solution where phi - beta - theta < 0 (the wedge cannot stand): refused
with a ValueError that names the parameters (``check``).

Pressure on the back face (traction per unit face area, Pa), at elevation z between the base of the
retained soil z_base and its top z_top (H = z_top - z_base, depth d = z_top - z):

* effective vertical stress sigma'(z) = sigma_q + gamma d above the water table (elevation z_w),
  sigma_q + gamma (z_top - z_w) + (gamma_sat - gamma_w)(z_w - z) below it; the surcharge q (Pa, per
  unit area of the backfill surface) enters as sigma_q = q cos(alpha) / cos(alpha - beta) (the
  equivalent height of soil: Das, Coulomb's pressure with a surcharge; q for a level backfill and a
  vertical back);
* static earth traction K_A sigma'(z) cos(alpha), inclined by delta (its integral over the face
  is K_A times the integral of sigma' over the height: 1/2 K_A gamma H^2 for dry soil);
* water (below the table) gamma_w (z_w - z), normal to the face, no friction: hydrostatic,
  unchanged by the shaking;
* seismic: the total active thrust is (1 - k_v) K_AE T with T = int sigma' dz (N/m): the
  static part scaled by (1 - k_v), plus the increment (1 - k_v)(K_AE - K_A) T distributed by
  ``increment``: ``"seed_whitman"`` (the default) places its resultant at 0.6 H above the base
  (Seed & Whitman 1970, "Design of earth retaining structures for dynamic loads", ASCE Specialty
  Conference on Lateral Stresses in the Ground; Kramer 1996 §11.6.1: the linear pressure
  (T / H)(1.6 - 1.2 d / H) cos(alpha) per unit K); ``"inverted_triangle"`` at 2/3 H ((T / H)
  2 (1 - d / H) cos(alpha)); ``"static"`` with the static distribution (Mononobe-Okabe's own
  assumption: the whole P_AE at the static resultant, H / 3 for dry soil without surcharge).
  Saturated soil: Mononobe-Okabe is applied to the effective (buoyant) weight below the table with
  the same theta, the water's inertia and its hydrodynamic pressure left out (Matsuzawa et al.
  1985's modified theta for restrained water and Westergaard's 7/12 k_h gamma_w h_w^2 for free
  water, e.g. EN 1998-5 Annex E, are not applied): the simplest defensible choice, unconservative
  for a saturated backfill; it keeps the seismic part one multiple of a fixed distribution.

Each field is linear in z between the breakpoints z_base, z_w and z_top, so its integral over a
planar face (clipped at those elevations) is exact from the polygon's area, first and second
moments (``polygon_moments``): no quadrature. A stone's force is then, for any k_h, k_v,

    F = F_water + (1 - k_v) [K_A F_static + (K_AE(k_h, k_v) - K_A) F_increment]

with F_static and F_increment per unit K (``StoneLoads``), and likewise the moment about the stone's
centroid: ``WallLoads.at`` evaluates a whole time series of k_h at once. k_h(t) from the base
acceleration: ``k_h_from_acceleration`` (only the part towards the soil; when the ground accelerates
away from the soil the static pressure is kept, never reduced).

Units SI: lengths m, unit weights N/m^3, pressures Pa, forces N, moments N m, angles rad.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.optimize import brentq

from drystone.geometry import polyhedron
from drystone.kept import Kept
from drystone.units import GRAVITY

#: unit weight of water (N/m^3): 1000 kg/m^3 times the simulations' default gravity
GAMMA_WATER = 1000.0 * GRAVITY
#: horizontal directions from the wall into the soil
INTO_SOIL = {"+x": (0, 1.0), "-x": (0, -1.0), "+y": (1, 1.0), "-y": (1, -1.0)}
#: height of the seismic increment's resultant above the base, as a fraction of H; None: the
#: static distribution (see the module docstring for the sources)
INCREMENTS = {"seed_whitman": 0.6, "inverted_triangle": 2.0 / 3.0, "static": None}
DEFAULT_INCREMENT = "seed_whitman"
#: physical ranges (low, high, why) of the soil's numbers, SI: beyond them a case is in the wrong
#: unit or absurd (a surcharge of 1e300 Pa reached YADE as a non-finite kinetic energy)
RANGES = {
    "surcharge": (0.0, 1e6, "Pa", "1 MPa is the weight of about 50 m of soil over the backfill"),
    "gamma": (0.0, 3e4, "N/m^3", "unit weights of soils and fills are 12-23 kN/m^3"),
    "gamma_sat": (0.0, 3e4, "N/m^3", "unit weights of soils and fills are 12-23 kN/m^3"),
    "gamma_w": (9e3, 1.2e4, "N/m^3", "fresh to muddy or saline water"),
}
#: a face is on the back plane when its outward normal is within this angle (rad) of the plane's
#: and every corner within ``plane_tol`` (m, default below) of it: 1e-6 rad and 1e-6 m are far
#: above the round-off of generated coordinates (~1e-15 m) and far below a real step between two
#: faces of a stone
NORMAL_TOL = 1e-6
PLANE_TOL = 1e-6


def _deg(x: float) -> str:
    return f"{math.degrees(x):.6g} deg"


def seismic_angle(k_h, k_v=0.0):
    """theta = atan(k_h / (1 - k_v)) (rad), element-wise."""
    return np.arctan(np.asarray(k_h, dtype=float) / (1.0 - np.asarray(k_v, dtype=float)))


def max_k_h(phi: float, beta: float = 0.0, k_v: float = 0.0) -> float:
    """The largest k_h for which Mononobe-Okabe has a solution: (1 - k_v) tan(phi - beta)."""
    return (1.0 - k_v) * math.tan(phi - beta)


def check(phi: float, delta: float = 0.0, beta: float = 0.0, alpha: float = 0.0, k_h=0.0, k_v=0.0) -> None:
    """Refuse a parameter set (angles in rad) for which the Coulomb or Mononobe-Okabe
    coefficient is undefined or meaningless: a ValueError naming the parameters and values.
    ``k_h``, ``k_v`` may be arrays (a time series): the first offending sample is named."""
    if not 0.0 < phi < math.pi / 2:
        raise ValueError(f"phi = {_deg(phi)}: the soil's friction angle must be in (0, 90) deg")
    if not 0.0 <= delta <= phi:
        raise ValueError(f"delta = {_deg(delta)}, phi = {_deg(phi)}: the wall friction delta must be in [0, phi]")
    if not abs(beta) < math.pi / 2:
        raise ValueError(f"beta = {_deg(beta)}: the backfill slope must be in (-90, 90) deg")
    if not abs(alpha) < math.pi / 2:
        raise ValueError(f"alpha = {_deg(alpha)}: the batter of the back face must be in (-90, 90) deg")
    if math.cos(alpha - beta) <= 0.0:
        raise ValueError(f"alpha = {_deg(alpha)}, beta = {_deg(beta)}: the backfill surface folds over the back face")
    if phi - beta < 0.0:
        raise ValueError(f"phi - beta = {_deg(phi)} - {_deg(beta)} < 0: the backfill slope is steeper than "
                         f"the friction angle, no active wedge (Coulomb)")
    kh = np.atleast_1d(np.asarray(k_h, dtype=float))
    kv = np.broadcast_to(np.atleast_1d(np.asarray(k_v, dtype=float)), kh.shape)
    bad = np.flatnonzero(~(np.abs(kv) < 1.0))
    if bad.size:
        i = bad[0]
        raise ValueError(f"k_v = {kv[i]:.6g}{_at(i, kh.size)}: the vertical seismic coefficient must be in (-1, 1)")
    theta = seismic_angle(kh, kv)
    slack = phi - beta - theta
    bad = np.flatnonzero(~(slack >= 0.0))
    if bad.size:
        i = bad[0]
        raise ValueError(
            f"Mononobe-Okabe has no solution: phi - beta - theta = {math.degrees(phi):.6g} - "
            f"{math.degrees(beta):.6g} - {math.degrees(theta[i]):.6g} = {math.degrees(slack[i]):.6g} deg < 0 "
            f"(phi = {_deg(phi)}, beta = {_deg(beta)}, k_h = {kh[i]:.6g}, k_v = {kv[i]:.6g}{_at(i, kh.size)}, "
            f"theta = atan(k_h / (1 - k_v))); the largest k_h is (1 - k_v) tan(phi - beta) = "
            f"{max_k_h(phi, beta, kv[i]):.6g}")
    bad = np.flatnonzero(~(np.cos(delta + alpha + theta) > 0.0))
    if bad.size:
        i = bad[0]
        raise ValueError(f"delta + alpha + theta = {_deg(delta + alpha + theta[i])} >= 90 deg (delta = {_deg(delta)}, "
                         f"alpha = {_deg(alpha)}, k_h = {kh[i]:.6g}{_at(i, kh.size)}): no active thrust")


def _at(i: int, n: int) -> str:
    return f" at sample {i}" if n > 1 else ""


def mononobe_okabe_kae(phi: float, delta: float = 0.0, beta: float = 0.0, alpha: float = 0.0, k_h=0.0, k_v=0.0):
    """Mononobe-Okabe's active coefficient K_AE (Kramer 1996 eq. 11.13; angles rad), element-wise
    over arrays of k_h, k_v; refused (``check``) where it has no solution. P_AE = 1/2 K_AE gamma
    H^2 (1 - k_v)."""
    check(phi, delta, beta, alpha, k_h, k_v)
    theta = seismic_angle(k_h, k_v)
    root = np.sqrt(np.sin(delta + phi) * np.sin(phi - beta - theta)
                   / (np.cos(delta + alpha + theta) * math.cos(beta - alpha)))
    k = np.cos(phi - alpha - theta) ** 2 / (np.cos(theta) * math.cos(alpha) ** 2 * np.cos(delta + alpha + theta)
                                            * (1.0 + root) ** 2)
    return float(k) if np.ndim(k) == 0 else k


def coulomb_ka(phi: float, delta: float = 0.0, beta: float = 0.0, alpha: float = 0.0) -> float:
    """Coulomb's active coefficient K_A (Kramer 1996 eq. 11.6, Das; angles rad): K_AE at
    k_h = k_v = 0. P_A = 1/2 K_A gamma H^2, inclined by delta from the face normal."""
    return mononobe_okabe_kae(phi, delta, beta, alpha, 0.0, 0.0)


@dataclass(frozen=True)
class EarthPressure:
    """The retained soil and the wall's back plane (SI, angles rad).

    ``gamma`` unit weight above the water table (N/m^3), ``phi``, ``delta``, ``beta``, ``alpha``
    as in the module docstring; ``into_soil`` the horizontal direction from the wall into the
    soil (+x, -x, +y, -y); ``back`` the coordinate along that axis (x or y, m, platform frame, not
    signed by the direction) of the back plane at ``z_base``; ``z_base``, ``z_top`` the elevations
    (m) of the base and the top of the retained soil against the wall; ``surcharge`` q (Pa) per
    unit area of the backfill surface; ``water_level`` the elevation of the water table (m; None:
    dry); ``gamma_sat`` the unit weight below it (N/m^3; default ``gamma``); ``gamma_w`` water's
    (N/m^3); ``increment`` the distribution of the seismic increment (``INCREMENTS``)."""

    gamma: float
    phi: float
    z_top: float
    z_base: float
    into_soil: str = "+y"
    back: float = 0.0
    delta: float = 0.0
    beta: float = 0.0
    alpha: float = 0.0
    surcharge: float = 0.0
    water_level: float | None = None
    gamma_sat: float | None = None
    gamma_w: float = GAMMA_WATER
    increment: str = DEFAULT_INCREMENT

    def __post_init__(self):
        check(self.phi, self.delta, self.beta, self.alpha)
        if self.into_soil not in INTO_SOIL:
            raise ValueError(f"into_soil = {self.into_soil!r}: one of {', '.join(INTO_SOIL)}")
        if self.increment not in INCREMENTS:
            raise ValueError(f"increment = {self.increment!r}: one of {', '.join(INCREMENTS)}")
        if not self.gamma > 0:
            raise ValueError(f"gamma = {self.gamma} N/m^3: the soil's unit weight must be positive")
        if not self.z_top > self.z_base:
            raise ValueError(f"z_top = {self.z_top} m, z_base = {self.z_base} m: the top must be above the base")
        if not self.surcharge >= 0:
            raise ValueError(f"surcharge = {self.surcharge} Pa: must be >= 0")
        for key, v in (("surcharge", self.surcharge), ("gamma", self.gamma), ("gamma_sat", self.gamma_sat_),
                       ("gamma_w", self.gamma_w)):
            lo, hi, unit, why = RANGES[key]
            if not lo <= v <= hi:
                raise ValueError(f"{key} = {v:g} {unit}: must be in [{lo:g}, {hi:g}] {unit} ({why})")
        if self.water_level is not None:
            if self.water_level > self.z_top:
                raise ValueError(f"water_level = {self.water_level} m above z_top = {self.z_top} m: free water "
                                 f"above the backfill is not modelled")
            if not self.gamma_sat_ > self.gamma_w:
                raise ValueError(f"gamma_sat = {self.gamma_sat_} N/m^3 <= gamma_w = {self.gamma_w} N/m^3: "
                                 f"the buoyant unit weight must be positive")

    # -- derived quantities ------------------------------------------------------------
    @property
    def gamma_sat_(self) -> float:
        return self.gamma if self.gamma_sat is None else self.gamma_sat

    @property
    def height(self) -> float:
        """H = z_top - z_base (m)."""
        return self.z_top - self.z_base

    @property
    def ka(self) -> float:
        return coulomb_ka(self.phi, self.delta, self.beta, self.alpha)

    def kae(self, k_h, k_v=0.0):
        return mononobe_okabe_kae(self.phi, self.delta, self.beta, self.alpha, k_h, k_v)

    @property
    def horizontal(self) -> np.ndarray:
        """Unit horizontal vector from the wall into the soil."""
        axis, sign = INTO_SOIL[self.into_soil]
        e = np.zeros(3)
        e[axis] = sign
        return e

    @property
    def normal(self) -> np.ndarray:
        """Unit normal of the back plane pointing into the soil: cos(alpha) e_h + sin(alpha) e_z."""
        n = math.cos(self.alpha) * self.horizontal
        n[2] = math.sin(self.alpha)
        return n

    @property
    def offset(self) -> float:
        """c with normal . x = c on the back plane (m)."""
        axis, _ = INTO_SOIL[self.into_soil]
        x0 = np.zeros(3)
        x0[axis] = self.back
        x0[2] = self.z_base
        return float(self.normal @ x0)

    @property
    def earth_direction(self) -> np.ndarray:
        """Unit direction of the earth thrust on the wall: -cos(delta) n + sin(delta) s, s the
        unit vector down the face."""
        n = self.normal
        s = -np.array([0.0, 0.0, 1.0]) + n[2] * n
        s /= np.linalg.norm(s)
        return -math.cos(self.delta) * n + math.sin(self.delta) * s

    @property
    def water_direction(self) -> np.ndarray:
        return -self.normal

    def _z_water(self) -> float | None:
        """The water table's elevation if it lies above the base (m), else None."""
        if self.water_level is None or self.water_level <= self.z_base:
            return None
        return self.water_level

    def breakpoints(self) -> list[float]:
        zw = self._z_water()
        return [self.z_base] + ([zw] if zw is not None and zw < self.z_top else []) + [self.z_top]

    def sigma_v(self, z) -> np.ndarray:
        """Effective vertical stress sigma'(z) (Pa) in the retained soil, z_base <= z <= z_top."""
        z = np.asarray(z, dtype=float)
        sq = self.surcharge * math.cos(self.alpha) / math.cos(self.alpha - self.beta)
        zw = self._z_water()
        if zw is None:
            return sq + self.gamma * (self.z_top - z)
        dry = sq + self.gamma * (self.z_top - np.maximum(z, zw))
        return dry + (self.gamma_sat_ - self.gamma_w) * np.maximum(zw - z, 0.0)

    def thrust_integral(self) -> float:
        """T = int sigma'(z) dz from z_base to z_top (N/m): the active thrust per unit wall length
        is K T (exact: sigma' is linear between breakpoints, trapezoids)."""
        zs = np.array(self.breakpoints())
        s = self.sigma_v(zs)
        return float(np.sum(0.5 * (s[1:] + s[:-1]) * np.diff(zs)))

    # -- the three fields, linear in z piece by piece: value = a + b z -------------------
    def fields(self) -> dict[str, list[tuple[float, float, float, float]]]:
        """Per field ("static" and "increment": traction per unit face area per unit K, Pa;
        "water": pore pressure, Pa) the pieces (z_lo, z_hi, a, b) on which it is a + b z."""
        ca = math.cos(self.alpha)
        zs = self.breakpoints()
        static, water = [], []
        zw = self._z_water()
        for lo, hi in zip(zs[:-1], zs[1:]):
            s_lo, s_hi = self.sigma_v([lo, hi])
            b = (s_hi - s_lo) / (hi - lo)
            static.append((lo, hi, ca * (s_lo - b * lo), ca * b))
            if zw is not None and hi <= zw:
                water.append((lo, hi, self.gamma_w * zw, -self.gamma_w))
        eta = INCREMENTS[self.increment]
        if eta is None:
            increment = list(static)
        else:  # (T / H)(u + v d / H) cos(alpha), d = z_top - z: resultant at eta H above the base
            h, t = self.height, self.thrust_integral()
            u, v = 6.0 * eta - 2.0, 6.0 - 12.0 * eta
            increment = [(self.z_base, self.z_top, ca * t / h * (u + v * self.z_top / h), -ca * t / h * v / h)]
        return {"static": static, "increment": increment, "water": water}

    def pressure(self, z, k_h=0.0, k_v=0.0) -> tuple[np.ndarray, np.ndarray]:
        """The earth traction (Pa per unit face area, inclined by delta) and the water pressure
        (Pa, normal) at elevations z, for given k_h, k_v (scalars)."""
        z = np.asarray(z, dtype=float)
        f = self.fields()
        ka = self.ka
        kae = self.kae(k_h, k_v)

        def value(pieces):
            out = np.zeros_like(z)
            for lo, hi, a, b in pieces:
                inside = (z >= lo) & (z <= hi) if lo == self.z_base else (z > lo) & (z <= hi)
                out = np.where(inside, a + b * z, out)
            return out

        earth = (1.0 - k_v) * (ka * value(f["static"]) + (kae - ka) * value(f["increment"]))
        return earth, value(f["water"])


# -- closed forms on a plane wall -------------------------------------------------------------
class Resultant(NamedTuple):
    """A thrust per unit wall length on the plane back face: its horizontal (towards the wall)
    and vertical (downwards) components (N/m) and the elevation (m) of the horizontal one's line
    of action (sum of int p_h z dz over sum of int p_h dz)."""
    horizontal: float
    vertical: float
    height: float


def _moments_1d(pieces) -> tuple[float, float]:
    """int (a + b z) dz and int (a + b z) z dz over the pieces, exact."""
    f0 = f1 = 0.0
    for lo, hi, a, b in pieces:
        f0 += a * (hi - lo) + b * (hi ** 2 - lo ** 2) / 2.0
        f1 += a * (hi ** 2 - lo ** 2) / 2.0 + b * (hi ** 3 - lo ** 3) / 3.0
    return f0, f1


def plane_wall_resultant(ep: EarthPressure, k_h: float = 0.0, k_v: float = 0.0) -> Resultant:
    """The total thrust (earth + water) per unit length of a plane back face from z_base to
    z_top, closed form: the earth traction integrates to (1 - k_v)[K_A T + (K_AE - K_A) T] along
    the face at delta + alpha below the horizontal, the water to int u dz horizontally and
    tan(alpha) int u dz vertically (per unit face length: divide by cos(alpha))."""
    f = ep.fields()
    ka, kae = ep.ka, ep.kae(k_h, k_v)
    ca = math.cos(ep.alpha)
    s0, s1 = _moments_1d(f["static"])
    i0, i1 = _moments_1d(f["increment"])
    w0, w1 = _moments_1d(f["water"])
    # a field of traction p per face area over dz / cos(alpha) of face: int p dz / cos(alpha)
    e0 = (1.0 - k_v) * (ka * s0 + (kae - ka) * i0) / ca
    e1 = (1.0 - k_v) * (ka * s1 + (kae - ka) * i1) / ca
    d = ep.delta + ep.alpha
    h0 = e0 * math.cos(d) + w0
    h1 = e1 * math.cos(d) + w1
    v0 = e0 * math.sin(d) + w0 * math.tan(ep.alpha)
    return Resultant(h0, v0, h1 / h0 if h0 > 0 else float("nan"))


# -- integration over the stones' faces -------------------------------------------------------
def polygon_moments(poly: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Area (m^2), first moment int x dA (m^3) and second moment int x x^T dA (m^4) of a planar
    convex polygon (k, 3), exact: a fan of triangles, each with area A, corners p_i and s = sum
    p_i, gives A s / 3 and A / 12 (sum p_i p_i^T + s s^T)."""
    p = np.asarray(poly, dtype=float)
    a0, a1, a2 = p[0], p[1:-1], p[2:]
    area = 0.5 * np.linalg.norm(np.cross(a1 - a0, a2 - a0), axis=1)
    s = a0 + a1 + a2
    first = (area[:, None] * s).sum(axis=0) / 3.0
    second = (np.einsum("k,ki,kj->ij", area, a1, a1) + np.einsum("k,ki,kj->ij", area, a2, a2)
              + area.sum() * np.outer(a0, a0) + np.einsum("k,ki,kj->ij", area, s, s)) / 12.0
    return float(area.sum()), first, second


def clip_z(poly: np.ndarray, z: float, keep_below: bool) -> np.ndarray:
    """The part of a convex polygon (k, 3) below (or above) the elevation z (Sutherland-Hodgman);
    an empty (0, 3) array if nothing is left."""
    out = []
    n = len(poly)
    for i in range(n):
        p, q = poly[i], poly[(i + 1) % n]
        dp, dq = (p[2] - z, q[2] - z) if keep_below else (z - p[2], z - q[2])
        if dp <= 0:
            out.append(p)
        if (dp < 0 < dq) or (dq < 0 < dp):
            out.append(p + (q - p) * (dp / (dp - dq)))
    return np.array(out).reshape(-1, 3)


#: the faces of stone parts, by their vertices: a case's stones are resolved again for every run
#: of a sweep, and a retained wall's loads computed again for every water level of a search
_FACES = Kept(4096)


def back_faces(parts, ep: EarthPressure, plane_tol: float = PLANE_TOL) -> list[np.ndarray]:
    """The faces (each a (k, 3) polygon, m, counter-clockwise seen from the soil) of a stone's
    convex parts (lists of vertices, m) that lie on the back plane with their outward normal
    into the soil."""
    n, c = ep.normal, ep.offset
    out = []
    for verts in parts:
        v = np.asarray(verts, dtype=float)
        f = _FACES.get((v.shape, v.tobytes()), lambda: polyhedron.faces(v))
        for normal, poly in zip(f.normals, f.polygons):
            if normal @ n >= math.cos(NORMAL_TOL) and np.all(np.abs(v[poly] @ n - c) <= plane_tol):
                out.append(v[poly])
    return out


class StoneLoads(NamedTuple):
    """One stone's loads: ``force`` and ``moment`` (3, 3) rows static (per unit K), increment
    (per unit K) and water (N; N m about ``centroid``, m); ``area`` the loaded back area (m^2)."""
    force: np.ndarray
    moment: np.ndarray
    centroid: np.ndarray
    area: float


FIELDS = ("static", "increment", "water")


def stone_loads(parts, ep: EarthPressure, centroid=None, plane_tol: float = PLANE_TOL) -> StoneLoads:
    """Integrate the three fields over a stone's exposed back faces (clipped at z_base, the water
    table and z_top), exactly (``polygon_moments``). ``parts``: the convex parts' vertex lists (m);
    ``centroid``: the point the moments are taken about (default: the stone's volume centroid)."""
    if centroid is None:
        vols = [polyhedron.volume_centroid(p) for p in parts]
        centroid = sum(v * c for v, c in vols) / sum(v for v, _ in vols)
    c = np.asarray(centroid, dtype=float)
    dirs = {"static": ep.earth_direction, "increment": ep.earth_direction, "water": ep.water_direction}
    fields = ep.fields()
    force, moment = np.zeros((3, 3)), np.zeros((3, 3))
    area = 0.0
    for face in back_faces(parts, ep, plane_tol):
        r = face - c  # moments about the centroid: small coordinates, little round-off
        for lo, hi in zip(ep.breakpoints()[:-1], ep.breakpoints()[1:]):
            piece = clip_z(clip_z(r, hi - c[2], True), lo - c[2], False)
            if len(piece) < 3:
                continue
            a0, s1, s2 = polygon_moments(piece)
            if a0 == 0.0:
                continue
            area += a0
            for k, name in enumerate(FIELDS):
                for plo, phi_, a, b in fields[name]:
                    if plo <= lo and hi <= phi_:  # this field's piece covers [lo, hi]
                        a_c = a + b * c[2]  # value = a_c + b r_z
                        f = a_c * a0 + b * s1[2]
                        fr = a_c * s1 + b * s2[:, 2]
                        force[k] += f * dirs[name]
                        moment[k] += np.cross(fr, dirs[name])
    return StoneLoads(force, moment, c, area)


@dataclass
class WallLoads:
    """Per stone coefficients of a whole wall, for cheap forces at every step: ``ids`` the stone
    ids; ``force``, ``moment`` (n, 3, 3) as in ``StoneLoads``."""

    ep: EarthPressure
    ids: list
    force: np.ndarray
    moment: np.ndarray
    centroids: np.ndarray

    def coefficients(self, k_h, k_v=0.0) -> tuple[np.ndarray, np.ndarray]:
        """(1 - k_v) K_A and (1 - k_v)(K_AE - K_A) for arrays k_h, k_v (refused, naming the first
        sample, where Mononobe-Okabe has no solution)."""
        kh = np.atleast_1d(np.asarray(k_h, dtype=float))
        kv = np.broadcast_to(np.atleast_1d(np.asarray(k_v, dtype=float)), kh.shape)
        ka = self.ep.ka
        kae = np.atleast_1d(self.ep.kae(kh, kv))
        return (1.0 - kv) * ka, (1.0 - kv) * (kae - ka)

    def at(self, k_h, k_v=0.0) -> tuple[np.ndarray, np.ndarray]:
        """Forces (T, n, 3) N and moments about the centroids (T, n, 3) N m for the time series
        k_h (T,), k_v (T,) or scalars: F_water + (1 - k_v)[K_A F_static + (K_AE - K_A) F_increment]."""
        cs, ci = self.coefficients(k_h, k_v)
        cs, ci = cs[:, None, None], ci[:, None, None]
        f = self.force[None, :, 2] + cs * self.force[None, :, 0] + ci * self.force[None, :, 1]
        m = self.moment[None, :, 2] + cs * self.moment[None, :, 0] + ci * self.moment[None, :, 1]
        return f, m


def wall_loads(stones: dict, ep: EarthPressure, centroids: dict | None = None,
               plane_tol: float = PLANE_TOL) -> WallLoads:
    """``WallLoads`` of the stones {id: [part vertices, ...]} (m); ``centroids`` {id: point}
    (default: each stone's volume centroid). Stones with no face on the back plane get zeros."""
    ids = list(stones)
    loads = [stone_loads(stones[i], ep, None if centroids is None else centroids[i], plane_tol) for i in ids]
    return WallLoads(ep, ids, np.array([s.force for s in loads]).reshape(-1, 3, 3),
                     np.array([s.moment for s in loads]).reshape(-1, 3, 3),
                     np.array([s.centroid for s in loads]).reshape(-1, 3))


def k_h_from_acceleration(acc, into_soil: str, g: float = GRAVITY, vertical: bool = False):
    """k_h(t) and k_v(t) from the base acceleration (T, 3) m/s^2 in the platform frame: k_h the
    component towards the soil over g, clipped at 0 (an acceleration away from the soil leaves
    the static pressure), k_v = -a_z / g (upward inertia of the wedge) if ``vertical``, else 0."""
    a = np.atleast_2d(np.asarray(acc, dtype=float))
    axis, sign = INTO_SOIL[into_soil]
    k_h = np.maximum(sign * a[:, axis] / g, 0.0)
    k_v = -a[:, 2] / g if vertical else np.zeros(len(a))
    return k_h, k_v


# -- a single retaining block: hand calculations -----------------------------------------------
class BlockLimits(NamedTuple):
    """Pseudo-static equilibrium of a rectangular block retaining soil (N, N m, m): its weight,
    the thrust's horizontal and vertical components and the elevation of the horizontal one
    above the block's base, the block's own horizontal inertia k_h W, the friction coefficient at
    which it starts to slide, and the moments about its toe (the front edge of its base) that
    overturn it and that restore it (it topples when overturning > restoring)."""
    weight: float
    thrust_h: float
    thrust_v: float
    thrust_height: float
    inertia: float
    mu_slide: float
    overturning: float
    restoring: float

    @property
    def overturning_ratio(self) -> float:
        """restoring / overturning moment: the factor of safety against toppling (< 1 topples)."""
        return self.restoring / self.overturning


def block_limits(width: float, height: float, length: float, density: float, ep: EarthPressure,
                 k_h: float = 0.0, k_v: float = 0.0, g: float = GRAVITY) -> BlockLimits:
    """Hand calculation for a box stone ``width`` (m, along ``ep.into_soil``) x ``height`` (m) x
    ``length`` (m, along the wall), of ``density`` (kg/m^3), standing on a rigid base at
    ``ep.z_base`` with its back face on the back plane (vertical: alpha = 0) and the soil up to
    ``ep.z_top`` <= its top, under the base's pseudo-static acceleration (k_h towards the soil,
    k_v): weight W = density g width height length; thrust P_h, P_v = ``plane_wall_resultant``
    times length at elevation z_P; the block's inertia k_h W (towards the wall's front, at mid
    height) and vertical load (1 - k_v) W + P_v. Sliding starts at
    mu = (P_h + k_h W) / ((1 - k_v) W + P_v); about the toe the overturning moment is
    P_h (z_P - z_base) + k_h W height / 2 and the restoring one (1 - k_v) W width / 2 + P_v width."""
    if ep.alpha != 0.0:
        raise ValueError(f"alpha = {_deg(ep.alpha)}: block_limits is for a vertical back face (alpha = 0)")
    if ep.z_top > ep.z_base + height * (1 + 1e-12):
        raise ValueError(f"z_top = {ep.z_top} m above the block's top {ep.z_base + height} m")
    r = plane_wall_resultant(ep, k_h, k_v)
    w = density * g * width * height * length
    ph, pv = r.horizontal * length, r.vertical * length
    inertia = k_h * w
    n = (1.0 - k_v) * w + pv
    over = ph * (r.height - ep.z_base) + inertia * height / 2.0
    rest = (1.0 - k_v) * w * width / 2.0 + pv * width
    return BlockLimits(w, ph, pv, r.height - ep.z_base, inertia, (ph + inertia) / n, over, rest)


def block_critical_k_h(width: float, height: float, length: float, density: float, ep: EarthPressure,
                       mu: float, k_v: float = 0.0, g: float = GRAVITY) -> tuple[float, float]:
    """The k_h at which the block of ``block_limits`` starts to slide (friction ``mu``) and to
    topple: 0.0 where it already does so statically, inf where it does not before Mononobe-Okabe's
    limit (1 - k_v) tan(phi - beta). Roots of the monotone margins, to 1e-14 in k_h."""
    top = max_k_h(ep.phi, ep.beta, k_v)

    def slide(kh):
        return block_limits(width, height, length, density, ep, kh, k_v, g).mu_slide - mu

    def topple(kh):
        b = block_limits(width, height, length, density, ep, kh, k_v, g)
        return b.overturning - b.restoring

    out = []
    for margin in (slide, topple):
        if margin(0.0) >= 0.0:
            out.append(0.0)
        elif margin(top) < 0.0:
            out.append(math.inf)
        else:
            out.append(brentq(margin, 0.0, top, xtol=1e-14, rtol=4 * np.finfo(float).eps))
    return out[0], out[1]
