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
  damping:     a dashpot pressure distributed over the contact patch (Eq. 8, see below)

Damping. Eq. 8 of the paper writes F_d = mu_0 A_c v_rel, but mu_0 = 0.08 or 0.8 as a
coefficient in N s/m^3 would be no damping at all; Abaqus defines contact damping as a
fraction of critical damping, applied node by node over the contact, which is how we read
mu_0 = xi. A dashpot pressure c v_n(x) integrated over the contact patch gives a force
c A v_n(p) at the patch centroid p plus a moment c R (w_B - w_A) from the patch's second
moment (R = int (s x n)(s x n)^T dA): a joint rocking about its middle is damped although
its centre does not move. The same holds tangentially while the contact sticks. The
coefficients are set so that each mode of the contact gets the fraction ``xi`` of its
critical damping: with K the contact's 6 x 6 stiffness at p (K_n A along n, K_t A in the
plane while sticking, K_n R in rocking; ``patch_stiffness``) and M the 6 x 6 effective
mass of the two bodies seen at p (the inverse of the mobility W, ``mobility``), the
damping matrix is C = 2 xi M^1/2 (M^-1/2 K M^-1/2)^1/2 M^1/2 = sum over the contact's modes
of 2 xi omega_k (M phi_k)(M phi_k)^T (``damping_matrix``). For one block on a rigid base
this is exact: bouncing, rocking and sliding each decay at xi (tests/test_damping.py);
for a flat joint with a diagonal M it is the dashpot pressure above with
c = 2 xi sqrt(K_n m / A) for the translation and 2 xi sqrt(K_n I / R) for rocking. While a
contact slips K has no tangential part, so neither has C. The damping is capped: the
normal dashpot never pulls (F_n + F_dn >= 0), the damping moment keeps the resultant of
the normal pressure inside the patch (its inertia ellipse, exact for a rectangle), and
spring plus dashpot stay within the Coulomb cap mu F_n (``cap_damping``).

A_c, the contact area, is estimated from the overlap volume, its extent along the joint's
face normal (``projection_direction``, from both blocks' vertices) and the depth of its
centroid (``contact_area``): exact for uniform and for wedge-shaped overlaps. The patch's
centroid and second moment come from the exact overlap (``drystone.overlap``).
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


def rotate_into_plane(fs, n) -> np.ndarray:
    """Carry stored shear forces into the current tangent plane, keeping their magnitude."""
    fs = np.asarray(fs, dtype=float)
    mag = np.linalg.norm(fs, axis=1)
    proj = fs - dot(fs, n)[:, None] * n
    pm = np.linalg.norm(proj, axis=1)
    scale = np.divide(mag, pm, out=np.zeros_like(mag), where=pm > 0)
    return proj * scale[:, None]


def shear_spring(n, v_rel, fs_prev, area, kt, mu, fn_el, dt):
    """Elastic tangential spring of m contacts, one step (Eqs. 6-7).

    n (m,3) unit normals A->B; v_rel (m,3) B's velocity relative to A at the contact point,
    m/s; fs_prev (m,3) stored shear force on B, N; area (m,) A_c m^2; kt (m,) N/m^3; mu
    (m,); fn_el (m,) elastic normal force N; dt s. Returns (fs (m,3) the new shear force on
    B, capped at mu F_n; slipping (m,) bool: the cap was reached).
    """
    n = np.asarray(n, dtype=float)
    v_rel = np.asarray(v_rel, dtype=float)
    vt = v_rel - dot(v_rel, n)[:, None] * n
    fs = rotate_into_plane(fs_prev, n) - (kt * area)[:, None] * vt * dt
    fmax = mu * fn_el
    fs_mag = np.linalg.norm(fs, axis=1)
    slipping = fs_mag > fmax
    scale = np.divide(fmax, fs_mag, out=np.ones_like(fs_mag), where=slipping)
    return fs * scale[:, None], slipping


def skew(r) -> np.ndarray:
    """(m,3,3) matrices [r]x with [r]x u = r x u."""
    r = np.asarray(r, float)
    z = np.zeros(len(r))
    return np.stack([np.stack([z, -r[:, 2], r[:, 1]], 1), np.stack([r[:, 2], z, -r[:, 0]], 1),
                     np.stack([-r[:, 1], r[:, 0], z], 1)], 1)


def mobility(ra, rb, inv_mass_a, inv_mass_b, inv_inertia_a, inv_inertia_b) -> np.ndarray:
    """Mobility W (m,6,6) of m contacts at their points: the relative twist acceleration
    (dv, dw) of B with respect to A per unit wrench (F, M) applied at the point to B (and
    the opposite to A). ra, rb (m,3) point minus each body's centroid, m; inv_mass (m,)
    1/kg (0: not moving); inv_inertia (m,3,3) global, 1/(kg m^2). W = sum over the two
    bodies of G^T diag(1/m, I^-1) G with G = [[1, 0], [[r]x, 1]]; M = W^-1 is the contact's
    effective mass (kg, kg m, kg m^2 blocks)."""
    W = np.zeros((len(ra), 6, 6))
    eye = np.eye(3)
    for r, im, ii in ((ra, inv_mass_a, inv_inertia_a), (rb, inv_mass_b, inv_inertia_b)):
        S = skew(r)
        iis = np.matmul(ii, S)  # I^-1 [r]x
        W[:, :3, :3] += im[:, None, None] * eye - np.matmul(S, iis)  # [r]x^T = -[r]x
        W[:, :3, 3:] -= np.matmul(S, ii)
        W[:, 3:, :3] += iis
        W[:, 3:, 3:] += ii
    return W


def patch_stiffness(n, area, patch_inertia, kn, kt, sticking) -> np.ndarray:
    """Stiffness K (m,6,6) of m contacts at their patch centroids, twist (dv, dw) -> wrench:
    K_n A n n^T + K_t A (1 - n n^T) in translation (K_t only where ``sticking``), K_n R in
    rotation with R = [n]x J [n]x^T = int (s x n)(s x n)^T dA (J the patch second moment,
    m^4, (m,3,3)). No twist stiffness about n: the elastic law has none."""
    n = np.asarray(n, float)
    nn = n[:, :, None] * n[:, None, :]
    K = np.zeros((len(n), 6, 6))
    kta = np.where(sticking, kt * area, 0.0)
    K[:, :3, :3] = (kn * area)[:, None, None] * nn + kta[:, None, None] * (np.eye(3) - nn)
    S = skew(n)
    K[:, 3:, 3:] = kn[:, None, None] * np.matmul(np.matmul(S, patch_inertia), S.transpose(0, 2, 1))
    return K


def damping_matrix(K, W, xi) -> tuple[np.ndarray, np.ndarray]:
    """C = 2 xi M^1/2 (M^-1/2 K M^-1/2)^1/2 M^1/2 with M = W^-1 (module docstring), for m
    contacts; also each contact's highest modal frequency omega_max (rad/s).

    Computed as C = 2 xi L^-T (L^T K L)^1/2 L^-1 with W = L L^T, L = U Lambda^1/2 from the
    eigen-decomposition of W; any factor of W gives the same C."""
    lam, U = np.linalg.eigh(W)
    lam = np.maximum(lam, 1e-300)
    sq = np.sqrt(lam)
    L = U * sq[:, None, :]
    B = np.matmul(np.matmul(L.transpose(0, 2, 1), K), L)
    B = 0.5 * (B + B.transpose(0, 2, 1))
    mu, V = np.linalg.eigh(B)
    om = np.sqrt(np.maximum(mu, 0.0))
    root = np.matmul(V * om[:, None, :], V.transpose(0, 2, 1))
    Linv = U / sq[:, None, :]  # L^-T = U Lambda^-1/2
    C = np.matmul(np.matmul(Linv, root), Linv.transpose(0, 2, 1))
    return 2.0 * np.asarray(xi, float)[:, None, None] * C, om.max(axis=1)


def cap_damping(fd, md, n, fn_el, fs, mu, lever, area, patch_inertia):
    """Cap the damping force fd (m,3) and moment md (m,3) at the patch centroid (module
    docstring): the normal dashpot never pulls; the damping moment keeps the resultant of
    the normal forces inside the patch's inertia ellipse {e: A e.J^+ e <= 3} (the
    rectangle's edges); the tangential dashpot plus the shear spring fs stays within
    mu fn_el. ``lever`` (m,3): overlap centroid (where fn_el acts) minus patch centroid."""
    n = np.asarray(n, float)
    fdn = dot(fd, n)
    fdn_c = np.maximum(fdn, -fn_el)
    fdt = fd - fdn[:, None] * n
    # tangential: spring + dashpot within the Coulomb cap (the dashpot is cut first)
    fmax = mu * fn_el
    tot = fs + fdt
    tm = np.linalg.norm(tot, axis=1)
    over = tm > fmax
    tot = tot * np.divide(fmax, tm, out=np.ones_like(tm), where=over)[:, None]
    fdt = tot - fs
    # moment: in-plane part; eccentricity e(s) = n x (M_el + s M_d) / N, N = fn_el + fdn_c
    N = fn_el + fdn_c
    m_el = cross(lever, fn_el[:, None] * n)
    m_el -= dot(m_el, n)[:, None] * n
    mdn = dot(md, n)[:, None] * n
    md_in = md - mdn
    Jp = np.linalg.pinv(patch_inertia, rcond=1e-9, hermitian=True)
    e0 = cross(n, m_el)
    e1 = cross(n, md_in)
    # q(s) = A (e0 + s e1).Jp.(e0 + s e1) <= 3 N^2 (times N^2 to avoid dividing by N)
    a2 = area * dot(e1, np.matmul(Jp, e1[:, :, None])[:, :, 0])
    a1 = 2.0 * area * dot(e0, np.matmul(Jp, e1[:, :, None])[:, :, 0])
    a0 = area * dot(e0, np.matmul(Jp, e0[:, :, None])[:, :, 0]) - 3.0 * N * N
    s = np.ones(len(n))
    need = (a2 + a1 + a0) > 0
    if need.any():
        disc = np.maximum(a1 * a1 - 4.0 * a2 * a0, 0.0)
        root = np.divide(-a1 + np.sqrt(disc), 2.0 * a2, out=np.zeros_like(a2), where=a2 > 0)
        s = np.where(need, np.clip(root, 0.0, 1.0), 1.0)
    return fdn_c[:, None] * n + fdt, s[:, None] * md_in + mdn


def critical_time_step(mass, stiffness, damping_ratio=0.0) -> float:
    """Critical step (s) of central differences for a mass on a spring with viscous
    damping: (2/omega)(sqrt(1 + xi^2) - xi), omega = sqrt(k/m)."""
    omega = np.sqrt(np.asarray(stiffness, float) / np.asarray(mass, float))
    xi = np.asarray(damping_ratio, float)
    return float(np.min(2.0 / omega * (np.sqrt(1.0 + xi * xi) - xi)))
