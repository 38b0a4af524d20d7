"""The penalty–Coulomb–damping contact law of the Sacsayhuaman paper (Eqs. 5–8), as numpy
kernels over arrays of contacts. No YADE import: ``yade_scripts/contact_engine.py`` feeds
these functions the contact geometry YADE computes and applies the forces they return.

Conventions (per contact k): ``n`` is the unit normal pointing from body A (YADE id1) to
body B (id2); forces returned act on B (A receives the opposite); ``v_rel`` is B's velocity
relative to A at the contact point (m/s). Units SI: K_n, K_t in N/m^3, areas m^2, forces N.

The law
  normal:      F_n = K_n V                  (V overlap volume, m^3; = K_n A_c delta for a
                                              flat joint: YADE's volumetric law, Eq. 5)
  tangential:  F_t += -K_t A_c v_t dt,  |F_t| <= mu F_n          (Eqs. 6-7, incremental)
  damping:     F_d = -c v,  c = 2 xi sqrt(k m_eff)                (Eq. 8, see below)

Eq. 8 of the paper writes F_d = mu_0 A_c v_rel, but mu_0 = 0.08 or 0.8 as a coefficient in
N s/m^3 would be no damping at all; Abaqus defines contact damping as a fraction of
critical damping, which is how we read mu_0 = xi: the normal dashpot is c_n = 2 xi
sqrt(K_n A_c m_n) and the tangential one (acting only while the contact sticks) is
c_t = 2 xi sqrt(K_t A_c m_t), with m_n, m_t the effective masses of the two bodies at the
contact point along the normal and along the sliding direction (``effective_mass``:
1/m = sum over the moving bodies of 1/m_i + (r_i x u).I_i^-1 (r_i x u); a fixed body adds
nothing). At a contact away from the centroid's axis (a block rocking on an edge) that
mass is a fraction of the block's: taking the whole mass would overdamp the contact's own
mode and make the explicit dashpot unstable (a step-to-step oscillation). The normal
dashpot never pulls: F_n + F_dn >= 0. The total tangential force (spring + dashpot) never
exceeds mu F_n.

A_c, the contact area, is estimated from the overlap volume, its extent along the joint's
face normal (``projection_direction``, from both blocks' vertices) and the depth of its
centroid (``contact_area``): exact for uniform and for wedge-shaped overlaps.
"""
from __future__ import annotations

import numpy as np

#: ignore contacts thinner than this (m) or with no volume: failed intersections in
#: YADE leave such values behind
MIN_DEPTH = 1e-18


def cross(a, b) -> np.ndarray:
    """Row-wise cross product of (m, 3) arrays (faster than np.cross for small m)."""
    out = np.empty(np.broadcast(a, b).shape)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def dot(a, b) -> np.ndarray:
    """Row-wise dot product of (m, 3) arrays."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def combine(k1: float, k2: float) -> float:
    """Series combination of two penalty stiffnesses (equal values give the same value)."""
    return 2.0 * k1 * k2 / (k1 + k2)


def pair_properties(mat_a: dict, mat_b: dict, joint: dict | None = None) -> dict:
    """Joint properties between two materials: kn, kt in series, the smaller mu, the mean
    damping; ``joint`` overrides mu and damping for one pair of blocks."""
    p = {"kn": combine(mat_a["kn"], mat_b["kn"]), "kt": combine(mat_a["kt"], mat_b["kt"]),
         "mu": min(mat_a["mu"], mat_b["mu"]), "damping": 0.5 * (mat_a["damping"] + mat_b["damping"])}
    if joint:
        for k in ("mu", "damping"):
            if k in joint:
                p[k] = float(joint[k])
    return p


def projection_direction(n, faces_a, faces_b) -> np.ndarray:
    """Direction along which to measure each overlap's extent (m, 3).

    YADE's contact normal can differ from the joint's face normal by a fraction of a
    degree, and over a 0.2 m face that tilts the extent by more than the penetration
    itself. So the extent is measured along the face normal closest to n: the outward
    normal of a face of A (faces_a, (m, F, 3)) aligned with n, or of a face of B aligned
    with -n, whichever is closer. Exact for flat joints; for a block on its edge, it is the
    normal of the face it presses into. Returns (directions (m, 3), face_of_a (m,) bool:
    True where the chosen face belongs to A).
    """
    ca = np.matmul(faces_a, n[:, :, None])[:, :, 0]
    cb = -np.matmul(faces_b, n[:, :, None])[:, :, 0]
    ia, ib = ca.argmax(1), cb.argmax(1)
    k = np.arange(len(n))
    best_a = ca[k, ia] >= cb[k, ib]
    return np.where(best_a[:, None], faces_a[k, ia], -faces_b[k, ib]), best_a


def contact_area(volume, extent, centroid_depth) -> np.ndarray:
    """Contact area A_c (m^2) of thin overlaps between planar faces.

    Between rigid planar faces the overlap depth d varies linearly over the contact
    footprint. Three numbers are known: the volume V = int d dA, the largest depth
    d2 (``extent``) and the distance e of the overlap's centroid from the flat face it
    presses into (``centroid_depth``), e = int d^2 dA / (2 V). For a depth varying
    linearly from d1 to d2 across a rectangular footprint, e = (d1^2 + d1 d2 + d2^2) /
    (3 (d1 + d2)), which gives d1 and then A_c = 2 V / (d1 + d2). This is exact for a
    uniform overlap (d1 = d2, e = d/2: A_c = V/d) and for a wedge (a block rocking on an
    edge, d1 = 0, e = d2/3: A_c = 2V/d2), and insensitive to the tiny relative tilts
    (1e-4 rad) that halve V/d2 when the penetration is tens of micrometres.
    """
    v = np.asarray(volume, dtype=float)
    d2 = np.asarray(extent, dtype=float)
    ok = d2 > MIN_DEPTH
    d2s = np.where(ok, d2, 1.0)
    e = np.clip(np.asarray(centroid_depth, dtype=float), d2s / 3.0, d2s / 2.0)
    b = d2s - 3.0 * e
    disc = np.maximum(b * b - 4.0 * (d2s * d2s - 3.0 * e * d2s), 0.0)
    d1 = np.clip(0.5 * (-b + np.sqrt(disc)), 0.0, d2s)
    return np.where(ok, 2.0 * v / (d1 + d2s), 0.0)


def effective_mass(u, ra, rb, inv_mass_a, inv_mass_b, inv_inertia_a, inv_inertia_b) -> np.ndarray:
    """Effective mass (kg) of a contact along unit directions u (m, 3): the inverse of the
    relative acceleration along u per unit pair of opposite forces along u applied at the
    contact point, r_a, r_b (m, 3) from each body's centre. ``inv_mass_*`` (m,) 1/kg (0 for
    a non-moving body), ``inv_inertia_*`` (m, 3, 3) global inverse inertia tensors
    (1/(kg m^2); zeros for a non-moving body)."""
    wa = cross(ra, u)
    wb = cross(rb, u)
    qa = dot(wa, np.matmul(inv_inertia_a, wa[:, :, None])[:, :, 0])
    qb = dot(wb, np.matmul(inv_inertia_b, wb[:, :, None])[:, :, 0])
    inv = inv_mass_a + inv_mass_b + qa + qb
    return np.divide(1.0, inv, out=np.full_like(inv, np.inf), where=inv > 0)


def rotate_into_plane(fs, n) -> np.ndarray:
    """Carry stored shear forces into the current tangent plane, keeping their magnitude."""
    fs = np.asarray(fs, dtype=float)
    mag = np.linalg.norm(fs, axis=1)
    proj = fs - dot(fs, n)[:, None] * n
    pm = np.linalg.norm(proj, axis=1)
    scale = np.divide(mag, pm, out=np.zeros_like(mag), where=pm > 0)
    return proj * scale[:, None]


def forces(n, v_rel, fn_el, fs_prev, area, kt, mu, xi, m_eff, dt):
    """One step of the tangential and damping law for m contacts.

    Parameters (arrays over contacts): n (m,3) unit normals A->B; v_rel (m,3) m/s;
    fn_el (m,) elastic normal force magnitude N (>= 0, from the volumetric law);
    fs_prev (m,3) stored elastic shear force on B, N; area (m,) A_c m^2; kt (m,) N/m^3;
    mu (m,); xi (m,) fraction of critical damping; m_eff (m,) kg, the contact's effective
    mass along the sliding direction; dt s.

    Returns (f_on_b (m,3) the force this law adds on B: normal dashpot + shear spring +
    shear dashpot; fs_new (m,3) the elastic shear force to store; slipping (m,) bool).
    The elastic normal force itself is applied by YADE's volumetric law.
    """
    n = np.asarray(n, dtype=float)
    v_rel = np.asarray(v_rel, dtype=float)
    vn = dot(v_rel, n)
    vt = v_rel - vn[:, None] * n
    kt_a = kt * area  # N/m
    fs = rotate_into_plane(fs_prev, n) - kt_a[:, None] * vt * dt
    fmax = mu * fn_el
    fs_mag = np.linalg.norm(fs, axis=1)
    slipping = fs_mag > fmax
    scale = np.divide(fmax, fs_mag, out=np.ones_like(fs_mag), where=slipping)
    fs = fs * scale[:, None]

    c_t = 2.0 * xi * np.sqrt(kt_a * m_eff)
    ftot = fs - np.where(slipping[:, None], 0.0, c_t[:, None] * vt)
    ftot_mag = np.linalg.norm(ftot, axis=1)
    over = ftot_mag > fmax
    ftot = ftot * np.divide(fmax, ftot_mag, out=np.ones_like(ftot_mag), where=over)[:, None]
    return ftot, fs, slipping


def normal_damping(n, v_rel, fn_el, kn, area, xi, m_eff) -> np.ndarray:
    """Normal dashpot force on B (m,3): -c_n v_n n, never pulling (F_n + F_dn >= 0)."""
    vn = dot(v_rel, n)
    c_n = 2.0 * xi * np.sqrt(kn * area * m_eff)
    fd = np.maximum(-c_n * vn, -fn_el)
    return fd[:, None] * n


def critical_time_step(mass, stiffness, damping_ratio=0.0) -> float:
    """Critical step (s) of central differences for a mass on a spring with viscous
    damping: (2/omega)(sqrt(1 + xi^2) - xi), omega = sqrt(k/m)."""
    omega = np.sqrt(np.asarray(stiffness, float) / np.asarray(mass, float))
    xi = np.asarray(damping_ratio, float)
    return float(np.min(2.0 / omega * (np.sqrt(1.0 + xi * xi) - xi)))
