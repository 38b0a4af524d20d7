"""The penalty–Coulomb–damping contact law of the Sacsayhuaman paper (Eqs. 5–8), as numpy
kernels over arrays of contacts. No YADE import: ``drystone/yade_scripts/contact_engine.py`` feeds
these functions the contact geometry YADE computes and applies the forces they return.

Conventions (per contact k): ``n`` is the unit normal pointing from body A (YADE id1) to
body B (id2); forces returned act on B (A receives the opposite); ``v_rel`` is B's velocity
relative to A at the contact point (m/s). Units SI: K_n, K_t in N/m^3, areas m^2, forces N.

The law
  normal:      F_n = K_n V                  (V overlap volume, m^3; = K_n A_c delta for a
                                              flat joint: YADE's volumetric law, Eq. 5)
  tangential:  F_t += -K_t A_c v_t dt,  |F_t| <= mu F_n          (Eqs. 6-7, incremental)
  twist:       M_t += -K_t J_p w_n dt,  |M_t| <= (2/3) mu F_n r_eq (reduced by F_t; not in
               the paper: the same shear springs resisting a rotation about n, ``twist_spring``)
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
plane while sticking, K_n R in rocking, K_t J_p in twist while sticking; ``patch_stiffness``) and M the 6 x 6 effective
mass of the two bodies seen at p (the inverse of the mobility W, ``mobility``), the
damping matrix is C = 2 xi M^1/2 (M^-1/2 K M^-1/2)^1/2 M^1/2 = sum over the contact's modes
of 2 xi omega_k (M phi_k)(M phi_k)^T (``damping_matrix``). For one block on a rigid base
this is exact: bouncing, rocking and sliding each decay at xi (tests/test_damping.py);
for a flat joint with a diagonal M it is the dashpot pressure above with
c = 2 xi sqrt(K_n m / A) for the translation and 2 xi sqrt(K_n I / R) for rocking. While a
contact slips K has no tangential part, so neither has C. A joint between stones of several
convex parts can be several contacts (one per pair of parts); each contact's C alone would
damp the joint's translation at sqrt(k) x xi for a joint cut into k equal contacts (C grows
as sqrt(K)), so the contacts of one pair of bodies share the ratio: each gets
xi sqrt(sum A_j) / sum sqrt(A_j) (``joint_share``; exact for the translation of coplanar
patches, 1 for a joint that is one contact). The damping is capped: the
normal dashpot never pulls (F_n + F_dn >= 0), the damping moment keeps the resultant of
the normal pressure inside the patch (its inertia ellipse, exact for a rectangle), and
spring plus dashpot stay within the Coulomb cap mu F_n (``cap_damping``).

A_c, the contact area, is estimated from the overlap volume, its extent along the joint's
face normal (``projection_direction``, from both blocks' vertices) and the depth of its
centroid (``contact_area``): exact for uniform and for wedge-shaped overlaps. The patch's
centroid and second moment come from the exact overlap (``drystone.mechanics.overlap``).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from drystone.geometry import blockfile as bf
from drystone import numba_cache
from drystone.numba_cache import FIRST, PARALLEL

numba_cache.install()  # numba's cache safe for processes compiling at once

#: ignore contacts thinner than this (m) or with no volume: failed intersections in
#: YADE leave such values behind
MIN_DEPTH = 1e-18
#: contact geometries: ``native`` (drystone.mechanics.overlap; this law only) and ``yade`` (YADE's
#: polyhedra intersection, CGAL)
DETECTIONS = ("native", "yade")


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


#: how a pair of materials combines each contact property (blockfile.CONTACT_PROPERTIES):
#: kn, kt in series, the smaller mu, the mean damping
PAIR_RULES = {"kn": combine, "kt": combine, "mu": min, "damping": lambda a, b: 0.5 * (a + b)}


def pair_properties(mat_a: dict, mat_b: dict, joint: dict | None = None) -> dict:
    """Contact properties between two materials (``PAIR_RULES``); ``joint`` overrides
    those of blockfile.JOINT_PROPERTIES (mu, damping) for one pair of blocks."""
    p = {k: PAIR_RULES[k](mat_a[k], mat_b[k]) for k in bf.CONTACT_PROPERTIES}
    for k in bf.JOINT_PROPERTIES:
        if joint and k in joint:
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


#: the torsional friction capacity of a patch over mu F_n r_eq, r_eq = sqrt(2 J_p / A)
#: (``twist_spring``): a uniformly pressed disc of radius a slips in torsion at
#: int mu p r dA = (2/3) mu F_n a, and its 2 J_p / A is a^2 (a square: 0.385 b against
#: the exact 0.383 b)
TWIST_CAPACITY = 2.0 / 3.0


@njit(cache=True)
def polar_moment(n, J) -> float:
    """J_p = int |s|^2 dA (m^4) of a patch about its centroid, from its second moment J
    (3, 3) and unit normal n (3,): trace(J) - n.J.n."""
    jn = 0.0
    for a in range(3):
        for b in range(3):
            jn += n[a] * J[a, b] * n[b]
    return J[0, 0] + J[1, 1] + J[2, 2] - jn


@njit(cache=True)
def twist_spring(mt0, wn, jp, area, kt, mu, fn_el, fs_mag, dt):
    """The twisting moment about n on B (N m) of one contact after one step: the patch's
    shear springs K_t resist a relative rotation about n with K_t J_p (J_p: ``polar_moment``,
    m^4; a twist psi moves the patch point s by psi |s|), incremental like the shear
    force, M_t = M_t0 - K_t J_p wn dt (wn: (w_B - w_A).n, rad/s), capped at
    TWIST_CAPACITY mu F_n r_eq sqrt(1 - (|F_t| / mu F_n)^2), r_eq = sqrt(2 J_p / A): the
    torsional friction of a uniformly pressed patch, reduced by the shear force the
    friction already carries (fs_mag, N; the elliptic limit surface of combined sliding
    and spinning, zero while the shear slips). Returns (M_t, the plastic work of the
    cap over the step, J: (M_t0 + M_t)(M* - M_t) / (2 K_t J_p) as ``energy.slip_work``).
    Without this spring a stuck patch had no twist stiffness, and the couple of the
    shear force at the overlap centroid (offset towards the toe) with the load made the
    twist of a steeply tilted block grow exponentially (docs/physics.md)."""
    k = kt * jp
    if k <= 0.0 or area <= 0.0:
        return 0.0, 0.0
    trial = mt0 - k * wn * dt
    fmax = mu * fn_el
    u = fs_mag / fmax if fmax > 0.0 else 1.0
    cap = TWIST_CAPACITY * fmax * np.sqrt(2.0 * jp / area) * np.sqrt(max(1.0 - u * u, 0.0))
    if abs(trial) <= cap:
        return trial, 0.0
    mt = cap if trial > 0.0 else -cap
    return mt, (mt0 + mt) * (trial - mt) / (2.0 * k)


@njit(cache=True)
def carried_share(before, now, f2, kt, both=False):
    """The share r of a contact's carried shear force (or twisting moment) that its patch
    still holds when its area (or polar moment) went from ``before`` to ``now`` (m^2 or
    m^4), and the elastic energy the patch lets go, J, f2 the carried force's square (N^2,
    or N^2 m^2), kt N/m^3. The law's patch is one spring K_t A holding a uniform traction,
    its energy f^2 / (2 K_t A). Where the patch shrank, r = now / before (the springs that
    left let go of their share of the traction): the energy falls to r times its value,
    instead of growing, by (1 - r) f2 / (2 K_t before). Where it grew, r = 1 (the springs
    that came in carry nothing yet), and the force spreads over the larger patch, as the
    law's next increments (K_t A) take it: its energy falls by f2 / (2 K_t) (1 / before -
    1 / now), what two springs let go when the loaded one shares its force with an unloaded
    one. Both counted as dissipated: the stored shear energy never changes with the area
    but downwards. With ``both`` (the carried elastic displacement, f = K_t A u_s: the force
    follows the area both ways), r = now / before and the change (1 - r) f2 / (2 K_t before).
    The opt-in law ``penalty_coulomb_area`` (drystone/mechanics/laws.py; docs/energy.md)."""
    if before <= 0.0 or now <= 0.0 or kt <= 0.0:
        return 1.0, 0.0
    r = now / before
    if r >= 1.0 and not both:
        return 1.0, 0.5 * f2 / kt * (1.0 / before - 1.0 / now)
    return r, (1.0 - r) * f2 / (2.0 * kt * before)


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
    m^4, (m,3,3)), plus the twist spring K_t J_p n n^T about n (``twist_spring``, J_p the
    polar moment, where ``sticking``)."""
    n = np.asarray(n, float)
    nn = n[:, :, None] * n[:, None, :]
    K = np.zeros((len(n), 6, 6))
    kta = np.where(sticking, kt * area, 0.0)
    K[:, :3, :3] = (kn * area)[:, None, None] * nn + kta[:, None, None] * (np.eye(3) - nn)
    S = skew(n)
    K[:, 3:, 3:] = kn[:, None, None] * np.matmul(np.matmul(S, patch_inertia), S.transpose(0, 2, 1))
    jp = np.trace(patch_inertia, axis1=1, axis2=2) - np.einsum("ma,mab,mb->m", n, patch_inertia, n)
    K[:, 3:, 3:] += np.where(sticking, kt * jp, 0.0)[:, None, None] * nn
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


# -- compiled kernel ------------------------------------------------------------------
# The same damping as mobility -> patch_stiffness -> damping_matrix -> cap_damping, one
# contact at a time without temporaries (the numpy functions above are the reference:
# tests/test_damping.py checks that both agree). W = L L^T by Cholesky, B = L^T K L, its
# square root in the contact's modal basis of an earlier step (a second-order series where
# that basis nearly diagonalises B, else cyclic Jacobi rotations, 6 x 6), and
# C u = 2 xi L^-T B^1/2 L^-1 u by triangular solves. A slipping contact's K has rank 3
# (no tangential or twist stiffness): there C u = 2 xi G (G^T W G)^-1/2 G^T u with K = G G^T,
# a 3 x 3 inverse square root, exact in the contact's modes (``_slip_damping``), where the
# 6 x 6 root's three zero eigenvalues cost Jacobi sweeps at every step and errors of ~1e-9.

# one call a sweep, not a rotation: LLVM does not inline a called rotation, and numba's
# inlining of it took 3.7 s of the step's compile at each of its two callers (docs/physics.md,
# Step engine)
@njit(cache=True, _nrt=False)
def _jacobi_sweep(A, V, n):
    """One cyclic-Jacobi sweep of the symmetric n x n A, in place: for each p < q in turn,
    the rotation J^T A J that zeroes A[p, q], and V <- V J (the eigenvectors gathered in V's
    columns). An element below round-off of both diagonal entries is already zero: no
    rotation. (``_jacobi_sqrt``'s 6 x 6 and ``_jacobi3``'s 3 x 3 sweeps.)"""
    for p in range(n - 1):
        for q in range(p + 1, n):
            apq = A[p, q]
            if abs(apq) <= 1e-17 * (abs(A[p, p]) + abs(A[q, q])):
                continue
            theta = (A[q, q] - A[p, p]) / (2.0 * apq)
            t = (1.0 if theta >= 0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
            c = 1.0 / np.sqrt(t * t + 1.0)
            s = t * c
            tau = s / (1.0 + c)
            # on the symmetric matrix (rows = columns)
            A[p, p] -= t * apq
            A[q, q] += t * apq
            A[p, q] = 0.0
            A[q, p] = 0.0
            for k in range(n):
                if k != p and k != q:
                    g = A[k, p]
                    h = A[k, q]
                    A[k, p] = g - s * (h + g * tau)
                    A[k, q] = h + s * (g - h * tau)
                    A[p, k] = A[k, p]
                    A[q, k] = A[k, q]
            for k in range(n):
                g = V[k, p]
                h = V[k, q]
                V[k, p] = g - s * (h + g * tau)
                V[k, q] = h + s * (g - h * tau)


# called, not inlined into the contact loop: inlined, numba took 290 s to compile the damping (47 s called)
@njit(cache=True, _nrt=False)  # it allocates nothing: no reference counts on its arrays
def _jacobi_sqrt(B, T, Q, s6, x6, A, V, warm):
    """B^1/2 = V diag(A) V^T for a symmetric positive semi-definite 6 x 6 B: on exit V
    holds B's eigenvectors (columns) and A's diagonal the square roots of its eigenvalues
    (negative round-off ones clipped to 0); returns (the largest eigenvalue, ``series``).
    With ``series`` the sweeps stopped early (or never started), V only nearly diagonalising
    B, and A is the whole square root of V^T B V to below round-off (``_series_root``):
    B^1/2 = V A V^T. T, Q (6 x 6), s6, x6 (6,): work arrays. On entry, with ``warm``, V is a
    basis to start from (the contact's eigenvectors of an earlier step, which nearly
    diagonalise B: usually the series alone then gives the root, and V stays as it came
    until a step's B has moved too far from it for the series, when sweeps refresh it;
    cyclic Jacobi is quadratically convergent; the result is a cold solve's to ~1e-9 of the
    largest eigenvalue's scale). The largest eigenvalue returned is V^T B V's largest
    diagonal entry, low by the square of V's misalignment (where the series is taken: up to
    ~1e-8 relative; 2e-9 measured on random contacts, tests/tolerances.py
    DAMPING_OMEGA_REL). A basis whose
    columns have drifted from unit length (round-off over many steps: > 1e-13) is
    re-orthonormalised first (modified Gram-Schmidt); one with a column far from unit
    length or not finite is not used."""
    n = 6
    drift = False
    if warm:
        # a basis that is not one (non-finite: a blown-up step) is dropped: start cold
        for j in range(n):
            d = 0.0
            for k in range(n):
                d += V[k, j] * V[k, j]
            if not d > 0.5:
                warm = False
                break
            if abs(d - 1.0) > 1e-13:
                drift = True
    if warm and drift:
        for j in range(n):
            for i in range(j):
                d = 0.0
                for k in range(n):
                    d += V[k, i] * V[k, j]
                for k in range(n):
                    V[k, j] -= d * V[k, i]
            d = 0.0
            for k in range(n):
                d += V[k, j] * V[k, j]
            d = 1.0 / np.sqrt(d)
            for k in range(n):
                V[k, j] *= d
    if warm:
        # A = V^T B V (T = B V)
        for i in range(n):
            for j in range(n):
                acc = 0.0
                for k in range(n):
                    acc += B[i, k] * V[k, j]
                T[i, j] = acc
        for i in range(n):
            for j in range(i, n):
                acc = 0.0
                for k in range(n):
                    acc += V[k, i] * T[k, j]
                A[i, j] = acc
                A[j, i] = acc
    else:
        for i in range(n):
            for j in range(n):
                A[i, j] = B[i, j]
                V[i, j] = 1.0 if i == j else 0.0
    series = False
    for _ in range(50):
        off = 0.0
        scale = 0.0
        for i in range(n):
            scale += A[i, i] * A[i, i]
            for j in range(i + 1, n):
                off += A[i, j] * A[i, j]
        if off <= 1e-26 * scale or scale == 0.0:
            break
        if _series_root(A, T, Q, s6, x6):  # nearly diagonal: its square root to below round-off, no sweep more
            series = True
            break
        _jacobi_sweep(A, V, n)
    lmax = 0.0
    for i in range(n):
        if A[i, i] > lmax:
            lmax = A[i, i]
    if series:
        for i in range(n):
            for j in range(n):
                A[i, j] = T[i, j]
        return lmax, True
    for k in range(n):
        A[k, k] = np.sqrt(A[k, k]) if A[k, k] > 0.0 else 0.0
    return lmax, False


#: ``_series_root``'s bound on the neglected terms of the square root (third order and the
#: fourth's leading part), over the largest square root: what the Jacobi sweeps leave when
#: they stop (``_jacobi_sqrt``: the off-diagonal part of V^T B V below 1e-13 of its
#: diagonal, taken as zero: the root then off by up to 1e-13 lambda_max / (s_i + s_j), at
#: least 5e-14 of the largest root). 1e-16 (round-off) made the series refuse a warm basis
#: turned by more than ~5e-6 (X / s): sticking contacts then swept at 26 % of a settled
#: running-bond wall's contact-steps and 61 % of its settling ones; 1e-13 reaches ~5e-5, and
#: the sweeps' share of that settling step fell from 18 to 10 % (``bench --only profile``)
SERIES_TOL = 1e-13


@njit(cache=True, _nrt=False)
def _series_root(A, S, Q, s, x):
    """The square root S (6 x 6) of a symmetric positive semi-definite A = D + E that is nearly
    diagonal (D its diagonal), when the expansion to second order gives it as closely as
    converged Jacobi sweeps would (SERIES_TOL); returns whether it did (S then written; else
    S is scratch). Q (6 x 6), s, x (6,): work arrays. With s_i = sqrt(D_ii), S = diag(s) + X
    + S2 + S3 + ..., each term matching S S to A at the next order: diag(s) X + X diag(s) =
    E, X_ij = E_ij / (s_i + s_j); S2_ij = -(X X)_ij / (s_i + s_j); S3_ij = -(X S2 + S2 X)_ij
    / (s_i + s_j); the fourth order -(X S3 + S3 X + S2 S2)_ij / (s_i + s_j). S = diag(s) + X
    + S2 is taken when the bound |(X S2 + S2 X)_ij| + |(S2 S2)_ij| <= q (x_i + x_j) + 6 q^2
    (q the largest |S2_kl|, x_i the sum of |X_ik| over k) is <= SERIES_TOL max(s) (s_i +
    s_j) for every i, j: the neglected terms are then below SERIES_TOL of the largest entry
    (the rest a further factor X / s smaller). This stands for the Jacobi sweeps (quadratic
    convergence: each sweep squares the off-diagonal part) at a fraction of their cost: a
    warm start (the previous step's modes) leaves off-diagonal terms that small (X / s up to
    SERIES_TOL^(1/3) ~ 5e-5) on a settled or shaken wall, where the first order alone
    (neglecting S2 ~ X X / s) needed a sweep first. A zero eigenvalue of B (a sticking line
    contact's rocking about its line; a slipping contact takes ``_slip_damping``) coupled to
    the others fails the test (s_i + s_j near 0), and the sweeps go on there."""
    n = 6
    smax = 0.0
    for i in range(n):
        s[i] = np.sqrt(A[i, i]) if A[i, i] > 0.0 else 0.0
        if s[i] > smax:
            smax = s[i]
    for i in range(n):  # X into S (zero diagonal), 1 / (s_i + s_j) into Q's upper triangle
        S[i, i] = 0.0
        Q[i, i] = 0.5 / s[i] if s[i] > 0.0 else 0.0
        for j in range(i + 1, n):
            d = s[i] + s[j]
            if d > 0.0:
                Q[i, j] = 1.0 / d
            elif A[i, j] == 0.0:
                Q[i, j] = 0.0
            else:
                return False
            S[i, j] = A[i, j] * Q[i, j]
            S[j, i] = S[i, j]
    q = 0.0  # S2 over Q's upper triangle
    for i in range(n):
        for j in range(i, n):
            acc = 0.0
            for k in range(n):
                acc += S[i, k] * S[k, j]
            if Q[i, j] == 0.0 and acc != 0.0:  # s_i + s_j = 0 with (X X)_ij nonzero
                return False
            Q[i, j] = -acc * Q[i, j]
            q = max(q, abs(Q[i, j]))
    for i in range(n):
        acc = 0.0
        for k in range(n):
            acc += abs(S[i, k])
        x[i] = acc
    lim = SERIES_TOL * smax
    for i in range(n):
        for j in range(i, n):
            if q * (x[i] + x[j]) + 6.0 * q * q > lim * (s[i] + s[j]):
                return False
    for i in range(n):
        S[i, i] = s[i] + Q[i, i]
        for j in range(i + 1, n):
            S[i, j] += Q[i, j]
            S[j, i] = S[i, j]
    return True


@njit(cache=True, _nrt=False)
def _add_body(W, IS, r, im, ii, c):
    """W += G^T diag(im, ii[c]) G for one body (see ``mobility``) at its point r[c], written
    out in 3 x 3 blocks with S = [r]x: [[im 1 - S ii S, -S ii], [ii S, ii]]; only the lower
    triangle, which the Cholesky factor reads (W is symmetric). IS: 3 x 3 work array."""
    r0, r1, r2 = r[c, 0], r[c, 1], r[c, 2]
    for a in range(3):  # ii S
        IS[a, 0] = ii[c, a, 1] * r2 - ii[c, a, 2] * r1
        IS[a, 1] = ii[c, a, 2] * r0 - ii[c, a, 0] * r2
        IS[a, 2] = ii[c, a, 0] * r1 - ii[c, a, 1] * r0
    W[0, 0] -= r1 * IS[2, 0] - r2 * IS[1, 0]  # (S ii S)[a, b], b <= a
    for b in range(2):
        W[1, b] -= r2 * IS[0, b] - r0 * IS[2, b]
    for b in range(3):
        W[2, b] -= r0 * IS[1, b] - r1 * IS[0, b]
    for a in range(3):
        W[a, a] += im
        for b in range(3):
            W[3 + a, b] += IS[a, b]
        for b in range(a + 1):
            W[3 + a, 3 + b] += ii[c, a, b]


@njit(cache=True, _nrt=False, inline="always")
def _wsym(W, i, j):
    """Element (i, j) of the symmetric W stored in its lower triangle."""
    return W[i, j] if i >= j else W[j, i]


@njit(cache=True, _nrt=False)  # it allocates nothing: no reference counts on its arrays
def _slip_damping(W, n0, n1, n2, kna, kn, u0, u1, u2, w0, w1, w2, l1, l2, v10, v11, v20, v21, twist, c, M, Q, y):
    """A slipping contact's C u / (2 xi) into y (6,), u = twist[c]; returns the largest
    omega^2 (0 where C is zero: no stiffness, or no mobility). W: the mobility's lower
    triangle; kna = K_n A; (u, w) a basis of the plane normal to n in which the patch's
    second moment has the eigenvalues l1, l2 along v1, v2 (its eigenvectors in that basis).
    M, Q (3 x 3): work arrays.

    While a contact slips, K = G G^T with G (6 x 3) of the columns sqrt(K_n A) (n, 0) and
    sqrt(K_n l_k) (0, n x e_k), e_k = v_k[0] u + v_k[1] w (K_n [n]x J [n]x^T = sum_k K_n l_k
    (n x e_k)(n x e_k)^T; no tangential or twist stiffness). Then M^-1/2 K M^-1/2 = P P^T
    with P = W^1/2 G (M = W^-1), whose square root is P (P^T P)^-1/2 P^T, so that
    C = 2 xi G (G^T W G)^-1/2 G^T: a 3 x 3 inverse square root (cyclic Jacobi) for the 6 x 6
    root of a matrix of rank 3, whose null space (the tangential and twist motions) C then
    leaves exactly undamped; the omega^2 of the contact's modes are the eigenvalues of
    G^T W G. A mode of l_k <= 0 (a line contact) is left out: its column is zero."""
    sa = np.sqrt(kna)
    a0, a1, a2 = sa * n0, sa * n1, sa * n2  # G's column 0, translational
    e10, e11, e12 = v10 * u0 + v11 * w0, v10 * u1 + v11 * w1, v10 * u2 + v11 * w2
    e20, e21, e22 = v20 * u0 + v21 * w0, v20 * u1 + v21 * w1, v20 * u2 + v21 * w2
    s1 = np.sqrt(kn * l1) if l1 > 0.0 else 0.0
    s2 = np.sqrt(kn * l2) if l2 > 0.0 else 0.0
    # G's columns 1, 2, rotational: sqrt(K_n l_k) n x e_k (rows 0 and 1 of Q for now)
    Q[0, 0], Q[0, 1], Q[0, 2] = s1 * (n1 * e12 - n2 * e11), s1 * (n2 * e10 - n0 * e12), s1 * (n0 * e11 - n1 * e10)
    Q[1, 0], Q[1, 1], Q[1, 2] = s2 * (n1 * e22 - n2 * e21), s2 * (n2 * e20 - n0 * e22), s2 * (n0 * e21 - n1 * e20)
    # M = G^T W G
    m00 = 0.0
    for i in range(3):
        wa = _wsym(W, i, 0) * a0 + _wsym(W, i, 1) * a1 + _wsym(W, i, 2) * a2
        m00 += (a0, a1, a2)[i] * wa
    M[0, 0] = m00
    for k in range(2):
        m0k = 0.0
        for i in range(3):  # a^T W_tr b_k, W_tr[i, j] = W[3 + j, i]
            m0k += (a0, a1, a2)[i] * (W[3, i] * Q[k, 0] + W[4, i] * Q[k, 1] + W[5, i] * Q[k, 2])
        M[0, 1 + k] = m0k
        M[1 + k, 0] = m0k
        for q in range(k, 2):
            mkq = 0.0
            for i in range(3):
                mkq += Q[k, i] * (_wsym(W, 3 + i, 3) * Q[q, 0] + _wsym(W, 3 + i, 4) * Q[q, 1]
                                  + _wsym(W, 3 + i, 5) * Q[q, 2])
            M[1 + k, 1 + q] = mkq
            M[1 + q, 1 + k] = mkq
    # t = G^T u
    t0 = a0 * twist[c, 0] + a1 * twist[c, 1] + a2 * twist[c, 2]
    t1 = Q[0, 0] * twist[c, 3] + Q[0, 1] * twist[c, 4] + Q[0, 2] * twist[c, 5]
    t2 = Q[1, 0] * twist[c, 3] + Q[1, 1] * twist[c, 4] + Q[1, 2] * twist[c, 5]
    b10, b11, b12, b20, b21, b22 = Q[0, 0], Q[0, 1], Q[0, 2], Q[1, 0], Q[1, 1], Q[1, 2]
    lmax = _jacobi3(M, Q)
    if lmax != lmax:  # a non-finite state: NaN wrenches, as the 6 x 6 path's
        for i in range(6):
            y[i] = np.nan
        return lmax
    if not lmax > 0.0:
        return lmax
    # x = M^-1/2 t = Q diag(mu^-1/2) Q^T t (modes of mu <= 0 carry nothing)
    p0 = Q[0, 0] * t0 + Q[1, 0] * t1 + Q[2, 0] * t2
    p1 = Q[0, 1] * t0 + Q[1, 1] * t1 + Q[2, 1] * t2
    p2 = Q[0, 2] * t0 + Q[1, 2] * t1 + Q[2, 2] * t2
    p0 = p0 / np.sqrt(M[0, 0]) if M[0, 0] > 0.0 else 0.0
    p1 = p1 / np.sqrt(M[1, 1]) if M[1, 1] > 0.0 else 0.0
    p2 = p2 / np.sqrt(M[2, 2]) if M[2, 2] > 0.0 else 0.0
    x0 = Q[0, 0] * p0 + Q[0, 1] * p1 + Q[0, 2] * p2
    x1 = Q[1, 0] * p0 + Q[1, 1] * p1 + Q[1, 2] * p2
    x2 = Q[2, 0] * p0 + Q[2, 1] * p1 + Q[2, 2] * p2
    # y = G x
    y[0], y[1], y[2] = a0 * x0, a1 * x0, a2 * x0
    y[3] = b10 * x1 + b20 * x2
    y[4] = b11 * x1 + b21 * x2
    y[5] = b12 * x1 + b22 * x2
    return lmax


@njit(cache=True, _nrt=False)
def _jacobi3(A, V):
    """Eigen-decomposition of a symmetric 3 x 3 A by cyclic Jacobi rotations, in place: on
    exit A's diagonal holds the eigenvalues, V's columns the eigenvectors; returns the
    largest eigenvalue (NaN for a non-finite A). Sweeps until the off-diagonal part is
    below 1e-13 of the diagonal's (its squares: 1e-26, as ``_jacobi_sqrt``)."""
    for i in range(3):
        for j in range(3):
            V[i, j] = 1.0 if i == j else 0.0
    for _ in range(50):
        off = A[0, 1] * A[0, 1] + A[0, 2] * A[0, 2] + A[1, 2] * A[1, 2]
        scale = A[0, 0] * A[0, 0] + A[1, 1] * A[1, 1] + A[2, 2] * A[2, 2]
        if not off > 1e-26 * scale:  # converged, zero, or not finite
            break
        _jacobi_sweep(A, V, 3)
    if not (A[0, 0] == A[0, 0] and A[1, 1] == A[1, 1] and A[2, 2] == A[2, 2]):
        return np.nan
    return max(A[0, 0], A[1, 1], A[2, 2])


@njit(cache=True)
def joint_share(ia, ib, nb, area):
    """(m,) factor on the damping ratio of each contact between bodies ia and ib (ids
    below ``nb``): sqrt(sum A) / sum sqrt(A) over the contacts of the same pair of bodies
    (areas m^2), 1 for a pair with one contact (module docstring, "Damping")."""
    m = len(ia)
    out = np.ones(m)
    if m < 2:
        return out
    key = np.empty(m, np.int64)
    for k in range(m):
        key[k] = min(ia[k], ib[k]) * nb + max(ia[k], ib[k])
    order = np.argsort(key, kind="mergesort")
    i = 0
    while i < m:
        j = i + 1
        while j < m and key[order[j]] == key[order[i]]:
            j += 1
        if j - i > 1:
            total = 0.0
            roots = 0.0
            for q in range(i, j):
                a = max(area[order[q]], 0.0)
                total += a
                roots += np.sqrt(a)
            if roots > 0.0:
                for q in range(i, j):
                    out[order[q]] = np.sqrt(total) / roots
        i = j
    return out


def damping_wrenches(n, parea, pj, kn, kt, xi, sticking, ra, rb, ima, imb, iia, iib, twist,
                     fn_el, fs, mu, lever):
    """Capped damping force and moment on B at each patch centroid (m,3) + (m,3), and each
    contact's highest modal frequency omega_max (m,) rad/s. Arguments as in ``mobility``,
    ``patch_stiffness``, ``damping_matrix`` and ``cap_damping``; ``twist`` (m,6) is B's
    velocity and angular velocity relative to A at the patch centroid. Every contact is
    solved from scratch (``damping_wrenches_warm`` without modes to start from), on one
    thread (its callers run in YADE's Python engines). The arrays are passed on contiguous:
    the compiled step's call of the same kernel, not another compilation of it."""
    m = len(parea)
    c = [np.ascontiguousarray(a, float) for a in (n, parea, pj, kn, kt, xi)]
    rest = [np.ascontiguousarray(a, float) for a in (ra, rb, ima, imb, iia, iib, twist, fn_el, fs, mu, lever)]
    return damping_wrenches_warm(*c, np.ascontiguousarray(sticking, np.bool_), *rest, np.zeros((m, 6, 6)),
                                 np.zeros(m, np.bool_), 1)


@njit(cache=True, parallel=PARALLEL)
def damping_wrenches_warm(n, parea, pj, kn, kt, xi, sticking, ra, rb, ima, imb, iia, iib, twist,
                          fn_el, fs, mu, lever, basis, warm, chunks):
    """``damping_wrenches`` with each contact's modal basis carried between steps:
    ``basis`` (m,6,6) holds on entry, where ``warm``, the contact's eigenvectors of an
    earlier step (of B = L^T K L, the scaled stiffness), and on exit the basis this step's
    square root was taken in, for every contact damped here (``_jacobi_sqrt``: refreshed
    when the step's B has moved too far from it). A basis that is not one (zeros, NaN) gives a cold
    solve. The result is the cold solve's to ~1e-9 of the largest wrench. A slipping
    contact takes neither (``_slip_damping``: its K has rank 3) and leaves its basis as it
    was, for when it sticks again.

    Threads: the contacts are cut into ``chunks`` contiguous ranges, shared among numba's
    threads (``numba.set_num_threads``; one range per thread the caller may run; one range:
    on the calling thread), each damped with its own work arrays (``_damp_range``); a contact's arithmetic does not
    depend on its range or thread: the same numbers for any count."""
    m = len(parea)
    fd = np.zeros((m, 3))
    md = np.zeros((m, 3))
    om = np.zeros(m)
    nt = max(1, chunks)  # (numba.get_num_threads() here would keep numba from caching the kernels)
    if nt == 1:  # on the calling thread
        _damp_range(FIRST, m, n, parea, pj, kn, kt, xi, sticking, ra, rb, ima, imb, iia, iib, twist, fn_el, fs, mu,
                    lever, basis, warm, fd, md, om)
        return fd, md, om
    for t in prange(nt):
        _damp_range(t * m // nt, (t + 1) * m // nt, n, parea, pj, kn, kt, xi, sticking, ra, rb, ima, imb, iia, iib,
                    twist, fn_el, fs, mu, lever, basis, warm, fd, md, om)
    return fd, md, om


@njit(cache=True)
def _damp_range(c0, c1, n, parea, pj, kn, kt, xi, sticking, ra, rb, ima, imb, iia, iib, twist, fn_el, fs, mu, lever,
                basis, warm, fd, md, om):
    """``damping_wrenches_warm``'s contacts c0 <= c < c1 into fd, md, om (and basis)."""
    W = np.empty((6, 6))  # its lower triangle
    IS = np.empty((3, 3))
    K = np.empty((6, 6))
    L = np.empty((6, 6))
    KL = np.empty((6, 6))
    B = np.empty((6, 6))
    T6 = np.empty((6, 6))  # work arrays of _jacobi_sqrt
    Q6 = np.empty((6, 6))
    s6 = np.empty(6)
    x6 = np.empty(6)
    w6 = np.empty(6)
    A6 = np.empty((6, 6))
    Rr = np.empty((3, 3))
    S = np.zeros((3, 3))
    SJ = np.empty((3, 3))
    y = np.empty(6)
    z = np.empty(6)
    M3 = np.empty((3, 3))  # work arrays of _slip_damping
    Q3 = np.empty((3, 3))
    for c in range(c0, c1):
        if xi[c] <= 0.0 or parea[c] <= 0.0:
            continue
        for i in range(6):
            for j in range(i + 1):
                W[i, j] = 0.0
        _add_body(W, IS, ra, ima[c], iia, c)
        _add_body(W, IS, rb, imb[c], iib, c)
        # K at the patch centroid: K_n A n n^T + K_t A (1 - n n^T); K_n [n]x J [n]x^T
        nc = n[c]
        n0, n1, n2 = nc[0], nc[1], nc[2]
        kta = kt[c] * parea[c] if sticking[c] else 0.0
        kna = kn[c] * parea[c]
        J = pj[c]
        # the patch second moment in the plane (2 x 2 in a basis u, w): its eigenvalues l1 >= l2
        # and eigenvectors v1, v2 (the slipping contact's stiffness and the moment's cap)
        if abs(n0) < 0.9:
            u0, u1, u2 = 0.0, -n2, n1
        else:
            u0, u1, u2 = n2, 0.0, -n0
        un = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        u0 /= un
        u1 /= un
        u2 /= un
        w0 = n1 * u2 - n2 * u1
        w1 = n2 * u0 - n0 * u2
        w2 = n0 * u1 - n1 * u0
        Ju0 = J[0, 0] * u0 + J[0, 1] * u1 + J[0, 2] * u2
        Ju1 = J[1, 0] * u0 + J[1, 1] * u1 + J[1, 2] * u2
        Ju2 = J[2, 0] * u0 + J[2, 1] * u1 + J[2, 2] * u2
        Jw0 = J[0, 0] * w0 + J[0, 1] * w1 + J[0, 2] * w2
        Jw1 = J[1, 0] * w0 + J[1, 1] * w1 + J[1, 2] * w2
        Jw2 = J[2, 0] * w0 + J[2, 1] * w1 + J[2, 2] * w2
        j11 = u0 * Ju0 + u1 * Ju1 + u2 * Ju2
        j12 = u0 * Jw0 + u1 * Jw1 + u2 * Jw2
        j22 = w0 * Jw0 + w1 * Jw1 + w2 * Jw2
        tr = j11 + j22
        dif = np.sqrt(0.25 * (j11 - j22) ** 2 + j12 * j12)
        l1 = 0.5 * tr + dif
        l2 = 0.5 * tr - dif
        # v1 from the row of the 2 x 2 without cancellation: where j12 is round-off and j22 >
        # j11, l1 - j22 is round-off too, and (l1 - j22, j12) points anywhere (a bed joint
        # along w, as an axis-aligned wall's: the cap then took the patch's axes wrong)
        if j11 >= j22:  # l1 - j22 >= j11 - j22 >= 0
            v10, v11 = l1 - j22, j12
        else:  # l1 - j11 >= j22 - j11 > 0
            v10, v11 = j12, l1 - j11
        vn = np.sqrt(v10 * v10 + v11 * v11)
        if vn > 0.0:
            v10 /= vn
            v11 /= vn
        else:  # j11 = j22 and j12 = 0: every direction is principal
            v10, v11 = 1.0, 0.0
        v20, v21 = -v11, v10
        if not sticking[c]:  # K of rank 3: C from its factor, no 6 x 6 root (_slip_damping)
            lmax = _slip_damping(W, n0, n1, n2, kna, kn[c], u0, u1, u2, w0, w1, w2, l1, l2, v10, v11, v20, v21,
                                 twist, c, M3, Q3, y)
            if lmax <= 0.0:  # no stiffness or no mobility: no damping (NaN: a blown-up state, NaN wrenches)
                continue
            om[c] = np.sqrt(lmax)
        else:  # the contact's 6 x 6: W = L L^T, B = L^T K L, B^1/2 (_jacobi_sqrt)
            ktj = kt[c] * polar_moment(nc, J)  # the twist spring
            # [n]x J [n]x^T
            S[0, 1], S[0, 2], S[1, 0], S[1, 2], S[2, 0], S[2, 1] = -n2, n1, n2, -n0, -n1, n0
            for a in range(3):
                for q in range(3):
                    SJ[a, q] = S[a, 0] * J[0, q] + S[a, 1] * J[1, q] + S[a, 2] * J[2, q]
            for a in range(3):
                for b in range(3):
                    Rr[a, b] = SJ[a, 0] * S[b, 0] + SJ[a, 1] * S[b, 1] + SJ[a, 2] * S[b, 2]
            for a in range(3):  # (the blocks off the diagonal are zero, never read)
                for b in range(3):
                    nn = nc[a] * nc[b]
                    K[a, b] = kna * nn + kta * ((1.0 if a == b else 0.0) - nn)
                    K[3 + a, 3 + b] = kn[c] * Rr[a, b] + ktj * nn
            # Cholesky W = L L^T (L's lower triangle; its upper one is zero, never read)
            ok = True
            for i in range(6):
                for j in range(i + 1):
                    s = W[i, j]
                    for k in range(j):
                        s -= L[i, k] * L[j, k]
                    if i == j:
                        if s <= 0.0:
                            ok = False
                            break
                        L[i, i] = np.sqrt(s)
                    else:
                        L[i, j] = s / L[j, j]
                if not ok:
                    break
            if not ok:
                continue
            # B = L^T K L (K block diagonal, L lower triangular: the sums skip their zero terms)
            for i in range(6):
                lo = 0 if i < 3 else 3
                for j in range(lo + 3):  # KL[i, j] = 0 for j > lo + 2
                    acc = 0.0
                    for k in range(max(lo, j), lo + 3):
                        acc += K[i, k] * L[k, j]
                    KL[i, j] = acc
            for i in range(6):
                for j in range(i, 6):
                    acc = 0.0
                    for k in range(max(i, 3) if j > 2 else i, 6):
                        acc += L[k, i] * KL[k, j]
                    B[i, j] = acc
            for i in range(6):
                for j in range(i + 1, 6):
                    B[j, i] = B[i, j]
            V6 = basis[c]
            lmax, series = _jacobi_sqrt(B, T6, Q6, s6, x6, A6, V6, warm[c])
            om[c] = np.sqrt(lmax)
            # y = L^-1 u (forward), z = B^1/2 y, w = L^-T z (backward); wrench = -2 xi w
            for i in range(6):
                s = twist[c, i]
                for k in range(i):
                    s -= L[i, k] * y[k]
                y[i] = s / L[i, i]
            for k in range(6):  # z = B^1/2 y = V A6 V^T y (A6 diagonal unless ``series``)
                s = 0.0
                for i in range(6):
                    s += V6[i, k] * y[i]
                z[k] = s
                w6[k] = A6[k, k] * s
            if series:
                for k in range(6):
                    for j in range(6):
                        if j != k:
                            w6[k] += A6[k, j] * z[j]
            for i in range(6):
                s = 0.0
                for k in range(6):
                    s += V6[i, k] * w6[k]
                z[i] = s
            for i in range(5, -1, -1):
                s = z[i]
                for k in range(i + 1, 6):
                    s -= L[k, i] * y[k]
                y[i] = s / L[i, i]
        f0 = -2.0 * xi[c] * y[0]
        f1 = -2.0 * xi[c] * y[1]
        f2 = -2.0 * xi[c] * y[2]
        m0 = -2.0 * xi[c] * y[3]
        m1 = -2.0 * xi[c] * y[4]
        m2 = -2.0 * xi[c] * y[5]
        # caps (cap_damping): no pull, Coulomb, resultant inside the patch ellipse
        fdn = f0 * n0 + f1 * n1 + f2 * n2
        fdn_c = max(fdn, -fn_el[c])
        fmax = mu[c] * fn_el[c]
        t0 = fs[c, 0] + f0 - fdn * n0
        t1_ = fs[c, 1] + f1 - fdn * n1
        t2_ = fs[c, 2] + f2 - fdn * n2
        tm = np.sqrt(t0 * t0 + t1_ * t1_ + t2_ * t2_)
        sc = fmax / tm if tm > fmax else 1.0
        fd[c, 0] = fdn_c * n0 + t0 * sc - fs[c, 0]
        fd[c, 1] = fdn_c * n1 + t1_ * sc - fs[c, 1]
        fd[c, 2] = fdn_c * n2 + t2_ * sc - fs[c, 2]
        N = fn_el[c] + fdn_c
        lv = lever[c]
        # m_el = fn (lever x n) in the plane
        e0x = lv[1] * n2 - lv[2] * n1
        e0y = lv[2] * n0 - lv[0] * n2
        e0z = lv[0] * n1 - lv[1] * n0
        mel_n = e0x * n0 + e0y * n1 + e0z * n2
        melx = fn_el[c] * (e0x - mel_n * n0)
        mely = fn_el[c] * (e0y - mel_n * n1)
        melz = fn_el[c] * (e0z - mel_n * n2)
        mdn = m0 * n0 + m1 * n1 + m2 * n2
        mdx = m0 - mdn * n0
        mdy = m1 - mdn * n1
        mdz = m2 - mdn * n2
        # e0 = n x m_el, e1 = n x m_d (in plane)
        a0x = n1 * melz - n2 * mely
        a0y = n2 * melx - n0 * melz
        a0z = n0 * mely - n1 * melx
        a1x = n1 * mdz - n2 * mdy
        a1y = n2 * mdx - n0 * mdz
        a1z = n0 * mdy - n1 * mdx
        tol = 1e-9 * l1
        i1 = 1.0 / l1 if l1 > tol else 0.0
        i2 = 1.0 / l2 if l2 > tol else 0.0
        b00 = a0x * u0 + a0y * u1 + a0z * u2
        b01 = a0x * w0 + a0y * w1 + a0z * w2
        b10 = a1x * u0 + a1y * u1 + a1z * u2
        b11 = a1x * w0 + a1y * w1 + a1z * w2
        p0 = b00 * v10 + b01 * v11
        q0 = b00 * v20 + b01 * v21
        p1 = b10 * v10 + b11 * v11
        q1 = b10 * v20 + b11 * v21
        A2 = parea[c] * (i1 * p1 * p1 + i2 * q1 * q1)
        A1 = 2.0 * parea[c] * (i1 * p0 * p1 + i2 * q0 * q1)
        A0 = parea[c] * (i1 * p0 * p0 + i2 * q0 * q0) - 3.0 * N * N
        s = 1.0
        if A2 + A1 + A0 > 0.0:
            disc = max(A1 * A1 - 4.0 * A2 * A0, 0.0)
            s = (-A1 + np.sqrt(disc)) / (2.0 * A2) if A2 > 0.0 else 0.0
            s = min(max(s, 0.0), 1.0)
        md[c, 0] = s * mdx + mdn * n0
        md[c, 1] = s * mdy + mdn * n1
        md[c, 2] = s * mdz + mdn * n2
    return fd, md, om
