"""Linearised modal analysis of a block assembly on its joint springs (plain Python, no YADE).

Around a static configuration (the settled state after gravity, or any configuration
given by the blocks' world vertices), each free block has 6 degrees of freedom: the
translation u of its centroid (m) and a rotation vector theta (rad) about it, in global
axes; DOFs a block may not use (YADE's ``blocked_dofs`` letters: x y z translations,
X Y Z rotations) are left out. The generalised forces Q(q) are those of the project's law
(``drystone/mechanics/contact.py``) without damping, evaluated from the exact overlap geometry
(``drystone.mechanics.overlap.all_contacts``) of the perturbed configuration:

* normal: F_n = K_n V along the contact normal, at the overlap centroid (for a flat joint
  the resultant of a Winkler pressure K_n x penetration, so the rotational stiffness
  K_n I of the footprint comes out of the moving centroid);
* tangential: a spring K_t A_c on the relative tangential displacement, at the contact
  point, of the two blocks' material points that were at the overlap centroid in the
  static configuration (A_c and that point fixed at their static values; no stored
  tangential force: the static configuration's shear forces are not recorded);
* twist: the law's twist spring (``contact.twist_spring``), a moment -K_t J_p psi n about
  the contact normal, psi = (theta_j - theta_i) . n the two blocks' relative rotation about
  it from the static configuration (J_p the patch's polar moment there, ``contact.polar_moment``):
  the same K_t J_p n n^T the damping's ``patch_stiffness`` holds, so a stone on a single flat
  joint has a torsional mode, omega^2 = K_t J_p / I_n (for a b x d footprint under a box,
  K_t A / m: the sliding spring's);
* gravity: m g at each centroid.

A stone of several convex parts (a re-entrant stone; a YADE clump) is one rigid body: its
mass, centroid and inertia are the union's (``drystone.geometry.massprops``), its parts are
shapes of that body in the overlap search (``overlap.contacts_of_shapes``: parts of one
stone never pair), so there is one contact per pair of parts of different stones, each with
its own normal and tangential springs as above, and their forces and moments are summed
on the stones. A stone cut into parts along planes that no other stone touches has the
contacts, hence the modes, of the same stone in one piece.

The recorded settled state is not an equilibrium of this model: the tangential forces
the joints stored while settling are not recorded, so the springs start unloaded there and
inclined joints are out of balance (up to ~40 % of a stone's weight on the Sacsayhuaman
wall). ``equilibrium`` therefore first finds the nearby static configuration q* with
Q(q*) = 0 by Newton's method on K (the tangential springs anchored at the settled state
carry the shear that balances the joints, as the stored forces would), and the modes are
those of K(q*).

K = -dQ/dq by differences (``stiffness``): steps of ``rel_step`` times the median overlap
depth V / A_c for translations and that divided by the block's size for rotations, so that
no overlap changes topology within a step and the truncation error, O(step^2) relative to
the depth, is ~1e-6. Where two stones' faces are flush (a stack of equal boxes, a wall's
front: coplanar faces, ``drystone.mechanics.overlap``), Q jumps as a stone moves across:
the overlap gains or loses a thin strip of side face, its normal tilts by (strip area) /
A_c one way or the other, and the normal force gets a sideways part (0.16 N either way on
the 0.2 x 0.2 m joint of two stacked 37 kg boxes). A jump is no stiffness, but a central
difference across it reads jump / (2 step), here 15 % of the joint's shear stiffness K_t
A_c, and the tower's first mode fell from 6.07 to 1.59 Hz. So each entry takes the central
difference over (-step, step) or the mean of the one-sided ones over (-2 step, -step) and
(step, 2 step), both O(step^2): a jump within (-step, step) spoils the first, one within 2
steps but outside it the second, and the one kept is the nearer to the median of the three
differences, which the jump leaves on the unspoiled side; where Q is smooth (and its slope
monotone) the median is the central one, kept. Gravity's geometric stiffness is not a
separate term: the preloaded normal forces move with the footprint (a block rotating by
theta about its centroid at height h above its joint shifts its footprint by -h theta
under the load W: the -W h of a rocking block) and the difference quotient sees it. The
generalised force of a rotation vector is T(theta)^T M (T the exponential map's tangent,
``_tangent``), exact virtual work for finite steps. The FD matrix is symmetric at an
equilibrium up to the tangential springs' path dependence; ``modes`` solves eigh((K +
K^T)/2, M) and reports the relative asymmetry and the static residual Q(0).

Units: SI (m, kg, N, rad, Hz); K_n, K_t in N/m^3.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from drystone.geometry import massprops
from drystone.mechanics import contact as law
from drystone.mechanics import overlap
from drystone.mechanics.contact import combine
from drystone.units import GRAVITY as G  # default gravity, m/s^2
_LETTERS = "xyzXYZ"


def mass_properties(vertices, density: float) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), centroid (m) and inertia tensor about the centroid (kg m^2, axes of the
    vertices' frame) of a stone of uniform density (kg/m^3): a convex polyhedron (its
    vertices, (n, 3)) or the union of convex parts (a list of such arrays), exact
    (``drystone.geometry.massprops``, the one home of a stone's mass properties)."""
    mp = massprops.mass_properties(_parts(vertices), density)
    return mp.mass, mp.centroid, mp.inertia


def _parts(vertices) -> list:
    """A block's convex parts: [its (n, 3) vertices] for a convex block, else the list
    of its parts' vertex arrays."""
    if isinstance(vertices, (list, tuple)) and len(vertices) and np.ndim(vertices[0]) == 2:
        return [np.asarray(p, float) for p in vertices]
    return [np.asarray(vertices, float)]


def _skew(w) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rotation(theta) -> np.ndarray:
    """Rotation matrix exp([theta]x) of a rotation vector (rad)."""
    th = np.asarray(theta, float)
    phi = float(np.linalg.norm(th))
    k = _skew(th)
    if phi < 1e-12:
        return np.eye(3) + k + 0.5 * k @ k
    return np.eye(3) + np.sin(phi) / phi * k + (1 - np.cos(phi)) / phi ** 2 * k @ k


def _tangent(theta) -> np.ndarray:
    """T(theta): spatial angular velocity = T theta_dot for R = exp([theta]x) R0."""
    th = np.asarray(theta, float)
    phi = float(np.linalg.norm(th))
    k = _skew(th)
    if phi < 1e-6:
        return np.eye(3) + 0.5 * k + k @ k / 6.0
    return np.eye(3) + (1 - np.cos(phi)) / phi ** 2 * k + (phi - np.sin(phi)) / phi ** 3 * k @ k


@dataclass
class Assembly:
    """Blocks at a static configuration.

    vertices: per block, world vertices (n, 3) m, or for a stone of several convex parts
    (a re-entrant stone, a YADE clump) the list of its parts' world vertices; moving: per block bool; density kg/m^3,
    kn, kt N/m^3 per block (pairs combine in series, ``drystone.mechanics.contact.combine``); mu
    (optional) per block, the pair's the smaller (``drystone.mechanics.contact.PAIR_RULES``);
    blocked: per block a string of blocked DOF letters (x y z X Y Z; "" for none); ids:
    block ids for the tables; gravity: m/s^2 vector, default (0, 0, -GRAVITY) (the analysis of a
    run takes the run's own: ``drystone.postprocess.identification.wall_assembly``)."""
    vertices: list
    moving: np.ndarray
    density: np.ndarray
    kn: np.ndarray
    kt: np.ndarray
    blocked: list = field(default_factory=list)
    ids: list = field(default_factory=list)
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -G]))
    mu: np.ndarray | None = None  # friction coefficient per block (pairs take the smaller), for ``balance``

    def __post_init__(self):
        nb = len(self.vertices)
        self.moving = np.asarray(self.moving, bool)
        self.density = np.broadcast_to(np.asarray(self.density, float), (nb,)).copy()
        self.kn = np.broadcast_to(np.asarray(self.kn, float), (nb,)).copy()
        self.kt = np.broadcast_to(np.asarray(self.kt, float), (nb,)).copy()
        self.blocked = list(self.blocked) or [""] * nb
        self.ids = list(self.ids) or list(range(nb))
        self.gravity = np.asarray(self.gravity, float)
        if self.mu is not None:
            self.mu = np.broadcast_to(np.asarray(self.mu, float), (nb,)).copy()
        if not (len(self.moving) == len(self.blocked) == len(self.ids) == nb):
            raise ValueError("vertices, moving, blocked and ids must have one entry per block")
        for b in self.blocked:
            if set(b) - set(_LETTERS):
                raise ValueError(f"blocked DOFs {b!r}: letters must be among {_LETTERS}")
        self.parts = [_parts(v) for v in self.vertices]
        props = [mass_properties(p, rho) for p, rho in zip(self.parts, self.density)]
        self.mass = np.array([p[0] for p in props])
        self.pos0 = np.array([p[1] for p in props])
        self.inertia = np.array([p[2] for p in props])
        self.size = np.array([float(np.ptp(np.vstack(p), axis=0).max()) for p in self.parts])
        # one convex shape per part, in its stone's frame (centred on the stone's centroid);
        # owner: the stone of each shape. Contacts are per pair of parts of different stones
        # (``overlap.contacts_of_shapes``), their forces summed on the stones
        self.owner = np.array([b for b, p in enumerate(self.parts) for _ in p], np.int64)
        self.shapes = overlap.Shapes([v - self.pos0[b] for b, p in enumerate(self.parts) for v in p])
        # the DOFs: (block index, component 0-5) of the moving blocks, blocked ones left out
        self.dofs = [(b, c) for b in np.flatnonzero(self.moving) for c in range(6)
                     if _LETTERS[c] not in self.blocked[b]]
        self._index = {d: k for k, d in enumerate(self.dofs)}
        ref = self.contacts(np.zeros(self.ndof))
        pj = self._shape_contacts(np.zeros(self.ndof))[7]
        jp = [law.polar_moment(n, J) for n, J in zip(ref["normal"], pj)]
        #: per contact (pair of shapes): the overlap centroid (m), area A_c (m^2) and polar
        #: moment J_p (m^4) of the static configuration
        self.reference = {(int(i), int(j)): (c.copy(), float(a), float(p))
                          for i, j, c, a, p in zip(ref["id1"], ref["id2"], ref["centroid"], ref["area"], jp)}
        self.reference_contacts = ref

    @property
    def ndof(self) -> int:
        return len(self.dofs)

    def dofs_of(self, b: int) -> list:
        """Indices of block ``b``'s DOFs (none for a block that does not move)."""
        return [k for k, (bb, _) in enumerate(self.dofs) if bb == b]

    def _configuration(self, q) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        nb = len(self.vertices)
        u = np.zeros((nb, 6))
        for k, (b, c) in enumerate(self.dofs):
            u[b, c] = q[k]
        rot = np.array([rotation(u[b, 3:]) for b in range(nb)])
        return self.pos0 + u[:, :3], rot, u

    def _shape_contacts(self, q):
        pos, rot, _ = self._configuration(q)
        s = self.shapes
        return overlap.contacts_of_shapes(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, self.owner, pos,
                                          rot, self.moving, overlap.TOL)

    def contacts(self, q) -> dict:
        """The overlaps of the configuration q (``overlap.all_contacts``' arrays): id1, id2
        the shapes (parts) in contact, block1, block2 their stones (indices into the
        blocks; equal to id1, id2 when every stone is convex)."""
        out = self._shape_contacts(q)[:6]
        c = dict(zip(("id1", "id2", "volume", "centroid", "normal", "area"), out))
        c["block1"], c["block2"] = self.owner[c["id1"]], self.owner[c["id2"]]
        return c

    def contact_forces(self, q) -> list:
        """Per contact of the configuration q: (stone index i, stone index j, point x (m),
        normal force F_n (N, >= 0), force on stone j (3,) N: normal plus tangential spring,
        moment on stone j (3,) N m: the twist spring's, about the normal)."""
        pos, rot, u = self._configuration(q)
        c = self.contacts(q)
        out = []
        for si, sj, i, j, v, x, n in zip(c["id1"], c["id2"], c["block1"], c["block2"], c["volume"], c["centroid"],
                                         c["normal"]):
            fn = combine(self.kn[i], self.kn[j]) * v
            fb = fn * n
            mb = np.zeros(3)
            ref = self.reference.get((int(si), int(sj)))
            if ref is not None:
                x0, a0, jp0 = ref
                kt = combine(self.kt[i], self.kt[j])
                ub = pos[j] - self.pos0[j] + (rot[j] - np.eye(3)) @ (x0 - self.pos0[j])
                ua = pos[i] - self.pos0[i] + (rot[i] - np.eye(3)) @ (x0 - self.pos0[i])
                s = ub - ua
                fb = fb - kt * a0 * (s - (s @ n) * n)
                mb = -kt * jp0 * float((u[j, 3:] - u[i, 3:]) @ n) * n
            out.append((int(i), int(j), x, float(fn), fb, mb))
        return out

    def generalised_forces(self, q) -> np.ndarray:
        """Q(q): per DOF, force (N) or T(theta)^T moment (N m) on the block (module docstring)."""
        pos, rot, u = self._configuration(q)
        nb = len(self.vertices)
        force = np.zeros((nb, 3))
        moment = np.zeros((nb, 3))
        force[self.moving] += self.mass[self.moving, None] * self.gravity
        for i, j, x, _, fb, mb in self.contact_forces(q):
            for b, f, m in ((j, fb, mb), (i, -fb, -mb)):
                if self.moving[b]:
                    force[b] += f
                    moment[b] += np.cross(x - pos[b], f) + m
        out = np.empty(self.ndof)
        for k, (b, comp) in enumerate(self.dofs):
            out[k] = force[b, comp] if comp < 3 else (_tangent(u[b, 3:]).T @ moment[b])[comp - 3]
        return out

    def friction_use(self, q) -> tuple[float, tuple | None]:
        """The largest |F_t| / (mu F_n) over the contacts of the configuration q (the
        tangential springs' forces; needs ``mu``) and that contact's stone ids."""
        c = self.contacts(q)
        worst, where = 0.0, None
        for (i, j, _, fn, fb, _), n in zip(self.contact_forces(q), c["normal"]):
            ft = float(np.linalg.norm(fb - (fb @ n) * n))
            cap = min(self.mu[i], self.mu[j]) * fn
            r = ft / cap if cap > 0 else (np.inf if ft > 0 else 0.0)
            if r > worst:
                worst, where = r, (self.ids[i], self.ids[j])
        return worst, where

    def steps(self, rel_step: float = 1e-3) -> np.ndarray:
        """Finite-difference step per DOF (m or rad): ``rel_step`` x the median overlap depth
        V / A_c of the static contacts (translations), divided by the block's size (rotations)."""
        rc = self.reference_contacts
        if len(rc["volume"]) == 0:
            raise ValueError("the static configuration has no contact: nothing holds the blocks")
        depth = float(np.median(rc["volume"] / rc["area"]))
        return np.array([rel_step * depth / (1.0 if c < 3 else self.size[b]) for b, c in self.dofs])

    def stiffness(self, rel_step: float = 1e-3, at=None) -> np.ndarray:
        """K = -dQ/dq (N/m, N, N m/rad) at the configuration ``at`` (default the static
        one, q = 0), h the DOF's step (``steps``): per entry, of the central difference over
        (-h, h) and the mean of the one-sided ones over (-2h, -h) and (h, 2h) (both second
        order), the one nearer the median of those three differences: the central one where
        Q is smooth, and where a force jumps within 2h (flush faces) the one the jump does
        not reach (module docstring)."""
        h = self.steps(rel_step)
        q0 = np.zeros(self.ndof) if at is None else np.asarray(at, float)
        K = np.empty((self.ndof, self.ndof))
        for k in range(self.ndof):
            e = np.zeros(self.ndof)
            e[k] = h[k]
            m2, m1, p1, p2 = (self.generalised_forces(q0 + f * e) for f in (-2.0, -1.0, 1.0, 2.0))
            below, central, above = -(m1 - m2) / h[k], -(p1 - m1) / (2 * h[k]), -(p2 - p1) / h[k]
            median = np.median(np.stack([below, central, above]), axis=0)
            outer = 0.5 * (below + above)  # second order too, and free of a jump within (-h, h)
            K[:, k] = np.where(np.abs(central - median) <= np.abs(outer - median), central, outer)
        return K

    def residual(self, q) -> float:
        """Largest out-of-balance force of the configuration q over the translation DOFs,
        divided by the block's weight (-)."""
        Q = self.generalised_forces(q)
        g = float(np.linalg.norm(self.gravity))
        return max((abs(Q[k]) / (self.mass[b] * g) for k, (b, c) in enumerate(self.dofs) if c < 3), default=0.0)

    def equilibrium(self, tol: float = 1e-6, max_iter: int = 30, rel_step: float = 1e-3) -> tuple[np.ndarray, list]:
        """The static configuration q* near q = 0 with Q(q*) = 0 (module docstring), by
        Newton's method with step halving on the residual; returns (q*, the residual of
        each iterate). Stops when the residual (``residual``) is below ``tol``."""
        q = np.zeros(self.ndof)
        hist = [self.residual(q)]
        for _ in range(max_iter):
            if hist[-1] < tol:
                break
            K = self.stiffness(rel_step, at=q)
            dq = np.linalg.lstsq(K, self.generalised_forces(q), rcond=None)[0]
            step = 1.0
            while step > 1e-3:
                r = self.residual(q + step * dq)
                if r < hist[-1]:
                    break
                step *= 0.5
            else:
                break  # no descent: leave it to the caller's report
            q = q + step * dq
            hist.append(r)
        return q, hist

    def mass_matrix(self) -> np.ndarray:
        """Block-diagonal mass matrix over the DOFs (kg, kg m^2)."""
        M = np.zeros((self.ndof, self.ndof))
        for k, (b, c) in enumerate(self.dofs):
            for l, (b2, c2) in enumerate(self.dofs):
                if b2 != b:
                    continue
                if c < 3 and c2 == c:
                    M[k, l] = self.mass[b]
                elif c >= 3 and c2 >= 3:
                    M[k, l] = self.inertia[b][c - 3, c2 - 3]
        return M

    def influence(self, direction) -> np.ndarray:
        """Rigid translation of every free block along a unit direction, over the DOFs."""
        d = np.asarray(direction, float)
        return np.array([d[c] if c < 3 else 0.0 for _, c in self.dofs])

    def point_displacement(self, shape, block_id, point) -> np.ndarray:
        """Displacement (m per unit modal coordinate) of a point (m) of a block: u + theta x r."""
        b = self.ids.index(block_id)
        u = np.zeros(6)
        for k, (bb, c) in enumerate(self.dofs):
            if bb == b:
                u[c] = shape[k]
        return u[:3] + np.cross(u[3:], np.asarray(point, float) - self.pos0[b])

    def damping(self, xi, at=None) -> np.ndarray:
        """Damping matrix C (ndof x ndof; N s/m, N s, N m s/rad) of the contact dashpots
        distributed over each contact patch, as the dynamic law applies them
        (``drystone.mechanics.contact.damping_matrix``: every mode of one contact's pair of blocks gets
        ``xi``), at the configuration ``at`` (default q = 0), every contact sticking. ``xi``:
        fraction of critical, a scalar or one per block (a pair takes the mean). A wrench at
        the patch centroid p acts on block b through T_b = [[1, -[p - x_b]x], [0, 1]]."""
        q = np.zeros(self.ndof) if at is None else np.asarray(at, float)
        xi_b = np.broadcast_to(np.asarray(xi, float), (len(self.vertices),))
        pos, rot, _ = self._configuration(q)
        ia, ib, _, _, n, area, pc, pj = self._shape_contacts(q)
        ia, ib = self.owner[ia], self.owner[ib]
        C = np.zeros((self.ndof, self.ndof))
        if len(ia) == 0:
            return C
        kn = np.array([combine(self.kn[i], self.kn[j]) for i, j in zip(ia, ib)])
        kt = np.array([combine(self.kt[i], self.kt[j]) for i, j in zip(ia, ib)])
        K = law.patch_stiffness(n, area, pj, kn, kt, np.ones(len(ia), bool))
        inv_m = np.where(self.moving, 1.0 / self.mass, 0.0)
        inv_i = np.array([rot[b] @ np.linalg.inv(self.inertia[b]) @ rot[b].T if self.moving[b]
                          else np.zeros((3, 3)) for b in range(len(self.mass))])
        ra, rb = pc - pos[ia], pc - pos[ib]
        W = law.mobility(ra, rb, inv_m[ia], inv_m[ib], inv_i[ia], inv_i[ib])
        Cl, _ = law.damping_matrix(K, W, 0.5 * (xi_b[ia] + xi_b[ib]))
        for k in range(len(ia)):
            B = np.zeros((6, self.ndof))
            for b, sign, r in ((ia[k], -1.0, ra[k]), (ib[k], 1.0, rb[k])):
                T = np.eye(6)
                T[:3, 3:] = -_skew(r)
                for d, (bb, c) in enumerate(self.dofs):
                    if bb == b:
                        B[:, d] += sign * T[:, c]
            C += B.T @ Cl[k] @ B
        return C

    @staticmethod
    def damped_modes(K, C, M) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Complex modes of M q'' + C q' + K q = 0 (state space): undamped-equivalent
        frequency |lambda| / 2 pi (Hz), damping ratio -Re(lambda) / |lambda| and the
        displacement parts of the eigenvectors (columns), ascending in frequency, one per
        conjugate pair; overdamped (real) roots left out."""
        n = len(M)
        Minv = np.linalg.inv(M)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
        lam, V = np.linalg.eig(A)
        keep = lam.imag > 1e-9 * np.abs(lam).max()
        lam, V = lam[keep], V[:n, keep]
        o = np.argsort(np.abs(lam))
        return np.abs(lam[o]) / (2 * np.pi), -lam[o].real / np.abs(lam[o]), V[:, o]

    def frequency_response(self, K, C, M, frequencies_hz, direction=(0.0, 1.0, 0.0)) -> np.ndarray:
        """Complex DOF displacements relative to the base per unit base acceleration
        (s^2; rows: frequencies) for a base motion along ``direction``:
        X = -(K - w^2 M + i w C)^-1 M r."""
        r = M @ self.influence(direction)
        return np.array([np.linalg.solve(K - (2 * np.pi * f) ** 2 * M + 2j * np.pi * f * C, -r)
                         for f in frequencies_hz])

    def modes(self, rel_step: float = 1e-3, direction=(0.0, 1.0, 0.0), equilibrate: bool = True, at=None) -> dict:
        """Natural frequencies (Hz, ascending), mass-normalised mode shapes (ndof x nmodes),
        participation factors Gamma = phi^T M r and effective-mass ratios Gamma^2 / total
        mass for a base motion along ``direction``; the stiffness's relative asymmetry
        |K - K^T| / |K| (Frobenius) and the static residual (largest |Q(0)| over the
        translation DOFs divided by the block's weight) before and after ``equilibrium``
        (with ``equilibrate``, the modes are those at q*; ``at``: those at that configuration,
        found elsewhere). Negative eigenvalues (an unstable or unrestrained configuration)
        give negative 'frequencies' (-sqrt|lambda|)."""
        if at is not None:
            q_star, hist = np.asarray(at, float), []
        else:
            q_star, hist = self.equilibrium(rel_step=rel_step) if equilibrate else (np.zeros(self.ndof), [])
        K = self.stiffness(rel_step, at=q_star)
        M = self.mass_matrix()
        ks = 0.5 * (K + K.T)
        lam, phi = linalg.eigh(ks, M)
        r = self.influence(direction)
        gamma = phi.T @ M @ r
        q0 = self.generalised_forces(np.zeros(self.ndof))
        w = np.array([self.mass[b] * np.linalg.norm(self.gravity) for b, c in self.dofs])
        tr = np.array([c < 3 for _, c in self.dofs])
        tr_q = np.array([abs(v) for (b, c), v in zip(self.dofs, q_star) if c < 3])
        return {"frequency_hz": np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi), "shapes": phi,
                "participation": gamma, "effective_mass_ratio": gamma ** 2 / float(self.mass[self.moving].sum()),
                "asymmetry": float(np.linalg.norm(K - K.T) / np.linalg.norm(K)),
                "residual": float(np.max(np.abs(q0[tr]) / w[tr])) if tr.any() else 0.0,
                "residual_at_equilibrium": hist[-1] if hist else None, "equilibrium_iterations": len(hist) - 1,
                "equilibrium_max_translation_m": float(tr_q.max()) if len(tr_q) else 0.0,
                "K": K, "M": M, "q_star": q_star, "dofs": [(self.ids[b], _LETTERS[c]) for b, c in self.dofs],
                "contacts": len(self.reference)}


#: an eigenvalue is zero (no stiffness) when |lambda| <= ZERO_EIGENVALUE_REL x the largest
#: |lambda|: the central-difference stiffness is exact to O(rel_step^2) = 1e-6 of its
#: largest entries (module docstring), so an eigenvalue within 10 times that of zero cannot
#: be told from it (a frequency below 0.3 % of the highest)
ZERO_EIGENVALUE_REL = 1e-5

#: the words for each DOF letter
MOTION = {"x": "translation along x", "y": "translation along y", "z": "translation along z",
           "X": "rotation about x", "Y": "rotation about y", "Z": "rotation about z"}


def stone_contacts(asm: Assembly) -> dict:
    """{stone id: number of contacts (pairs of parts) it has at the static configuration}."""
    rc = asm.contacts(np.zeros(asm.ndof))
    n = {i: 0 for i in asm.ids}
    for a, b in zip(rc["block1"], rc["block2"]):
        n[asm.ids[a]] += 1
        n[asm.ids[b]] += 1
    return n


def interpret(asm: Assembly, res: dict, zero_rel: float = ZERO_EIGENVALUE_REL) -> dict:
    """Read the eigenpairs of ``Assembly.modes`` (``res``) physically: per eigenpair (in
    ``res``'s order) its kind, "mode" (lambda > 0: a frequency), "zero" (|lambda| within
    ``zero_rel`` of the largest: no stiffness, a mechanism) or "unstable" (lambda < 0: the
    configuration is not a stable equilibrium), the share of the mode's kinetic energy of
    each stone (mass-normalised shapes: the shares sum to 1) and of each DOF letter (x y z
    translations, X Y Z rotations), the effective mass ratios for base motions along x, y
    and z, and for "zero" and "unstable" ones a one-line explanation naming the stone.
    Returns {"eigen": [per eigenpair], "contacts": {stone id: contacts}}."""
    f = np.asarray(res["frequency_hz"], float)
    lam = np.sign(f) * (2 * np.pi * f) ** 2
    scale = float(np.abs(lam).max()) if len(lam) else 0.0
    phi, M = res["shapes"], res["M"]
    total = float(asm.mass[asm.moving].sum())
    gammas = {a: phi.T @ M @ asm.influence(np.eye(3)[k]) for k, a in enumerate("xyz")}
    ncont = stone_contacts(asm)
    out = []
    for k in range(len(lam)):
        p = phi[:, k]
        e = p * (M @ p)
        e = e / e.sum() if e.sum() > 0 else e
        stones, letters = {}, {}
        for d, (b, c) in enumerate(asm.dofs):
            stones[asm.ids[b]] = stones.get(asm.ids[b], 0.0) + e[d]
            letters[_LETTERS[c]] = letters.get(_LETTERS[c], 0.0) + e[d]
        top = max(stones, key=stones.get)
        kind = "zero" if abs(lam[k]) <= zero_rel * scale else ("mode" if lam[k] > 0 else "unstable")
        item = {"kind": kind, "eigenvalue_rad2_s2": float(lam[k]),
                "effective_mass_ratio": {a: float(g[k] ** 2 / total) for a, g in gammas.items()},
                "stone_share": {b: float(s) for b, s in sorted(stones.items(), key=lambda x: -x[1])},
                "motion_share": {c: float(s) for c, s in letters.items()}, "dominant_stone": top}
        if kind != "mode":
            b = asm.ids.index(top)
            own = {_LETTERS[c]: e[d] for d, (bb, c) in enumerate(asm.dofs) if bb == b}
            motion = MOTION[max(own, key=own.get)]
            share = f"{100 * stones[top]:.0f} % of the mode"
            if kind == "unstable":
                item["explanation"] = (f"negative stiffness ({lam[k]:.3g} rad^2/s^2): stone {top} ({share}, mostly "
                                       f"{motion}, {ncont[top]} contact(s)) is not in stable equilibrium")
            elif ncont[top] == 0:
                item["explanation"] = f"stone {top} touches nothing: a free rigid-body motion ({motion})"
            else:
                item["explanation"] = (f"a mechanism: the joints give no stiffness to this motion of stone {top} "
                                       f"({share}, mostly {motion}, {ncont[top]} contact(s))")
        out.append(item)
    return {"eigen": out, "contacts": ncont}


#: the octagonal friction pyramid of ``balance``: |s| <= mu F_n imposed on 8 directions of
#: the tangent plane, which admits |s| up to mu F_n / cos(pi / 8) (8 % above the cone)
_CONE_SIDES = 8


def balance(asm: Assembly) -> dict:
    """Is the static configuration (q = 0) an equilibrium once the joints carry shear?

    The recorded settled state of a run is balanced by the normal forces K_n V (which the
    model sees) and by the tangential forces the joints stored while settling, capped at
    mu F_n (which it does not see: ``Assembly`` starts its springs unloaded). With s_c the
    shear of contact c in its tangent plane at its overlap centroid, two linear programmes
    (HiGHS; the friction cone as an octagonal pyramid, ``_CONE_SIDES``):

    * the smallest out-of-balance left on any stone by shears within friction,
      min over |s_c| <= mu_c F_n,c of max over the stones' DOFs of |Q + A s| (forces over
      the stone's weight W, moments over W times its size): ``residual``, its stone;
    * the least friction needed to balance every stone (to 1e-3 of ``BALANCE_TOL``), min of
      max_c |s_c| / (mu_c F_n,c): ``friction_use`` (on the pyramid: the true cone's lies
      between it and 1.082 times it), and the contact that sets it.

    Without ``mu`` the least-squares shear gives ``residual`` (no friction limit). Returns
    {"balanced": residual <= BALANCE_TOL, "residual", "residual_stone", "friction_use"
    (None when no shear balances the stones exactly, or without mu), "friction_contact"
    ((id, id)), "as_built_residual" (no shear), "as_built_stone"}. A contact with a
    friction use above 1 carries less than the shear the least-friction balance wants of
    it; the wall is then balanced only where ``residual`` says so."""
    from scipy.optimize import linprog

    q0 = np.zeros(asm.ndof)
    Q0 = asm.generalised_forces(q0)
    rc = asm.contacts(q0)
    g = float(np.linalg.norm(asm.gravity))
    nc = len(rc["id1"])
    A = np.zeros((asm.ndof, 2 * nc))
    scale = np.array([asm.mass[b] * g * (1.0 if c < 3 else asm.size[b]) for b, c in asm.dofs])
    fn = np.zeros(nc)
    mu = np.zeros(nc)
    for k in range(nc):
        i, j = int(rc["block1"][k]), int(rc["block2"][k])
        n, x = rc["normal"][k], rc["centroid"][k]
        fn[k] = combine(asm.kn[i], asm.kn[j]) * rc["volume"][k]
        mu[k] = min(asm.mu[i], asm.mu[j]) if asm.mu is not None else np.inf
        t1 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(n, t1)
        for col, t in ((2 * k, t1), (2 * k + 1, t2)):
            for b, sign in ((j, 1.0), (i, -1.0)):
                for d in asm.dofs_of(b):
                    c = asm.dofs[d][1]
                    A[d, col] += sign * (t[c] if c < 3 else np.cross(x - asm.pos0[b], t)[c - 3])
    As, bs = A / scale[:, None], -Q0 / scale

    def worst(r):
        if not len(r):
            return 0.0, None
        k = int(np.argmax(np.abs(r)))
        return float(abs(r[k])), asm.ids[asm.dofs[k][0]]

    built, built_stone = worst(bs)
    out = {"friction_use": None, "friction_contact": None, "as_built_residual": built, "as_built_stone": built_stone}
    if asm.mu is None or nc == 0:
        y = np.linalg.lstsq(As, bs, rcond=None)[0] if nc else np.zeros(0)
        out["residual"], out["residual_stone"] = worst(bs - As @ y)
        out["balanced"] = out["residual"] <= BALANCE_TOL
        return out
    cap = mu * fn
    Aw = As * np.repeat(cap, 2)[None, :]  # in the variables y_c = s_c / (mu_c F_n,c)
    ang = 2 * np.pi * np.arange(_CONE_SIDES) / _CONE_SIDES
    dirs = np.stack([np.cos(ang), np.sin(ang)], axis=1)
    nv = 2 * nc + 1
    cone = np.zeros((nc * _CONE_SIDES, nv))
    for k in range(nc):
        cone[k * _CONE_SIDES:(k + 1) * _CONE_SIDES, 2 * k:2 * k + 2] = dirs
    cost = np.zeros(nv)
    cost[-1] = 1.0
    free = [(None, None)] * (2 * nc)
    # 1. shears within friction (d_k . y_c <= 1), the largest out-of-balance e minimised
    ub = np.vstack([np.hstack([Aw, -np.ones((asm.ndof, 1))]), np.hstack([-Aw, -np.ones((asm.ndof, 1))]), cone])
    rhs = np.concatenate([bs, -bs, np.ones(len(cone))])
    lp = linprog(cost, A_ub=ub, b_ub=rhs, bounds=free + [(0, None)], method="highs")
    y = lp.x[:-1] if lp.status == 0 else np.linalg.lstsq(Aw, bs, rcond=None)[0]
    out["residual"], out["residual_stone"] = worst(bs - Aw @ y)
    # 2. balance (to BALANCE_TOL / 1000), the largest friction use t minimised (d_k . y_c <= t)
    cone[:, -1] = -1.0
    eq = np.hstack([Aw, np.zeros((asm.ndof, 1))])
    slack = 1e-3 * BALANCE_TOL
    lp = linprog(cost, A_ub=np.vstack([eq, -eq, cone]), b_ub=np.concatenate([bs + slack, slack - bs,
                                                                            np.zeros(len(cone))]),
                 bounds=free + [(None, None)], method="highs")
    if lp.status == 0:
        yc = lp.x[:-1].reshape(nc, 2)
        k = int(np.argmax((yc @ dirs.T).max(axis=1)))
        out["friction_use"] = float(lp.x[-1])
        out["friction_contact"] = (asm.ids[int(rc["block1"][k])], asm.ids[int(rc["block2"][k])])
    out["balanced"] = out["residual"] <= BALANCE_TOL
    return out


#: a stone is out of balance when the force left on it, shear included, exceeds 1e-3 of its
#: weight: the linearisation's preload (the normal forces that give gravity's geometric
#: stiffness) is then wrong by as much
BALANCE_TOL = 1e-3
