"""The energy balance of a run, accumulated at every step (numba kernels and numpy
references; no YADE import). ``contact_step.CompiledStep`` and the step engines
(drystone/yade_scripts/engines.py) call these; the recorder writes the sums
(histories.npz ``work_loads``, ``dissipated_damping``, ``dissipated_friction``) and the
summary their balance (drystone/postprocess/summary.py ``energy``). Units: J, SI.

The balance. With E_k the kinetic energy of the free blocks, E_el the elastic energy
stored in the contacts (normal and shear springs), D_damp the work done against the
contacts' damping forces and moments, D_fric the plastic work of Coulomb slip and W_loads
the work of the loads on the free blocks (the body force m g_eff(t): gravity, tilt and
base excitation; applied forces and [[loads]] such as the earth pressure; the velocity
jumps of a sine started as a displacement; the contact forces of kinematically moved
blocks, settlements),

    E_k + E_el + D_damp + D_fric - W_loads = constant.

Dissipations are positive when energy leaves the model; W_loads is positive when the
loads put energy in. For constant gravity alone W_loads = -(change of the potential
energy), which the histories also hold (``potential``).

The discrete scheme (leapfrog, as ``drystone.mechanics.integration``). Positions x_n and
contact forces F_n live at the steps t_n; velocities at the half steps, v_{n+1/2} =
v_{n-1/2} + dt (F_n / m + g_n), and the recorder gives E_k at t_{n-1/2}. For every body
and free direction the kinetic energy then changes exactly by

    E_k(n+1/2) - E_k(n-1/2) = (F_n + m g_n) . (v_{n-1/2} + v_{n+1/2}) / 2 dt,

the work of the step's forces over the centred displacement (x_{n+1} - x_{n-1}) / 2 (for
rotations about a fixed principal axis likewise with the torque; Fincham's scheme for a
tumbling body adds its own O(dt) drift of the orientation, drystone.mechanics.integration).
So each force held over step n is charged with the mean velocity
v_bar = (v_{n-1/2} + v_{n+1/2}) / 2 (``account``, after the step is integrated):

* W_loads += sum over free blocks (m g_n + F_ext) . v_bar dt on their free directions,
  plus the loads' moments M_ext . w_bar dt (earth pressure: a force on a face, its moment
  about the centroid; ``load_work``), and - F_c . v dt for every kinematically moved block (F_c the contact force on it: the
  driver that moves it supplies -F_c);
* D_damp -= sum over all bodies (F_d . v_bar + M_d . w_bar) dt, F_d and M_d the damping
  wrenches summed on each body (their pairs act on two bodies: the sum is the relative
  twist's work, also against a moved block).

The springs hold positions: F_n = -grad U(x_n). Their elastic energy is recorded at the
half step as (U(x_{n-1}) + U(x_n)) / 2 (the recorder); for a linear spring the work
sum over steps then telescopes to the change of U up to (k/4) (x_{n+1} - x_n)^2, i.e.
(omega dt)^2 / 2 of the kinetic energy of the mode: a bounded error of order dt^2 that
does not grow with the number of steps (leapfrog's shadow energy).

* Normal spring: F_n = K_n V along n at the overlap's centroid c is the resultant of a
  Winkler pressure K_n d(x) over the footprint, d the overlap's depth across the joint
  (its in-plane position is the depth-weighted centroid). Its potential is
  U_n = K_n / 2 int d^2 dA = K_n V e, e the distance of c from the flat face the overlap
  presses into (a flat joint: half the depth; a block rocking on an edge: a third of the
  deepest), exact for any shape pressing into a flat face and, to first order in the
  angle between them, for a thin wedge between two faces (``normal_energy``: the face of A
  or of B most nearly across n; the uniform-overlap energy V^2 K_n / (2 A) is 3/4 of a
  wedge's).
* Shear spring: U_t = |F_t|^2 / (2 K_t A). The slip of step n (over t_{n-1}..t_n, with
  v_{n-1/2}) takes the rotated previous force f0 to the trial f* = f0 - K_t A v_t dt, and
  the Coulomb cap returns it to f = f* mu F_n / |f*|. With the trapezoid rule over the
  same interval, the work of the shear force is (f0 + f) . (f0 - f*) / (K_t A) / 2 =
  -(change of U_t) - D_fric with D_fric = (f0 + f) . (f* - f) / (2 K_t A) >= 0, the
  return-mapping part (``slip_work``; zero while the contact sticks, mu F_n |du_plastic|
  while it slides steadily). It is centred at t_{n-1/2}: half is added when step n's
  forces are computed, half when the step is integrated, so that a sample taken between
  the two (energies at t_{n-1/2}) holds the slip up to t_{n-1/2}.

Accumulators: an array ``acc`` (3,) = (W_loads, D_damp, D_fric), J, from the run's start.
"""
from __future__ import annotations

import numpy as np
from numba import njit
from drystone import numba_cache

numba_cache.install()  # numba's cache safe for processes compiling at once

#: the accumulators' order in ``acc`` and the histories' keys
TERMS = ("work_loads", "dissipated_damping", "dissipated_friction")


@njit(cache=True)
def account(dt, g, F, T, Fd, Td, F_ext, moving, mass, lin_free, v0, w0, v1, w1, fric_half, acc):
    """Add one integrated step to ``acc`` (module docstring): the loads' work to acc[0],
    the damping's dissipation to acc[1], ``fric_half`` (J, the second half of the step's
    slip work) to acc[2]. ``g`` (3,) m/s^2; F, T (nb, 3) the forces and torques the step
    integrated (N, N m: contact plus applied); Fd, Td (nb, 3) the damping wrenches summed
    on each body; F_ext (nb, 3) the applied forces (N); moving (nb,) bool; mass (nb,) kg;
    lin_free (nb, 3) 1.0 on free directions; v0, w0 and v1, w1 (nb, 3) the velocities and
    angular velocities before and after the step (m/s, rad/s)."""
    nb = len(mass)
    wl = 0.0
    dd = 0.0
    for i in range(nb):
        if moving[i]:
            for a in range(3):
                if lin_free[i, a] > 0.0:
                    wl += (mass[i] * g[a] + F_ext[i, a]) * (0.5 * (v0[i, a] + v1[i, a]))
        else:  # a block moved by a stage (zero velocity for fixed ones): its driver's work
            for a in range(3):
                wl -= F[i, a] * (0.5 * (v0[i, a] + v1[i, a])) + T[i, a] * (0.5 * (w0[i, a] + w1[i, a]))
        for a in range(3):
            dd -= Fd[i, a] * (0.5 * (v0[i, a] + v1[i, a])) + Td[i, a] * (0.5 * (w0[i, a] + w1[i, a]))
    acc[0] += wl * dt
    acc[1] += dd * dt
    acc[2] += fric_half


@njit(cache=True)
def load_work(dt, c, Fb, Tb, moving, lin_free, rot_free, v0, w0, v1, w1):
    """Work (J) of the loads' wrench over one integrated step: sum over the moving bodies of
    F . v_bar dt on their free directions and M . w_bar dt on their free rotations (the
    work of a force on a face of a rigid body, F . v + M . w, M about its centroid), with
    F = sum_j c[j] Fb[j], M = sum_j c[j] Tb[j] (c (J,), Fb, Tb (J, nb, 3) N, N m:
    contact_step.applied_wrench) and the mean velocities of the step as in ``account``."""
    nj = len(c)
    w = 0.0
    for i in range(len(moving)):
        if not moving[i]:
            continue
        for a in range(3):
            f = 0.0
            t = 0.0
            for j in range(nj):
                f += c[j] * Fb[j, i, a]
                t += c[j] * Tb[j, i, a]
            w += lin_free[i, a] * f * (0.5 * (v0[i, a] + v1[i, a])) + rot_free[i, a] * t * (0.5 * (w0[i, a] + w1[i, a]))
    return w * dt


@njit(cache=True, _nrt=False)
def _face_depth(normals, offsets, nf, rot, pos, s, b, c, d, k, sign):
    """(alignment, depth) of the face of convex shape s (of body b) whose outward normal is
    closest to the direction sign x d[k] (sign +-1): the cosine between them and the
    distance (m) of the point c[k] inside the shape from that face's plane. normals (ns,
    F, 3), offsets (ns, F): the shapes' face planes N . x + D <= 0 in their bodies' frames;
    rot, pos the bodies' rotation matrices and positions. Indices, not slices: no array
    views to build per contact."""
    dl0 = sign * (rot[b, 0, 0] * d[k, 0] + rot[b, 1, 0] * d[k, 1] + rot[b, 2, 0] * d[k, 2])  # R^T d
    dl1 = sign * (rot[b, 0, 1] * d[k, 0] + rot[b, 1, 1] * d[k, 1] + rot[b, 2, 1] * d[k, 2])
    dl2 = sign * (rot[b, 0, 2] * d[k, 0] + rot[b, 1, 2] * d[k, 1] + rot[b, 2, 2] * d[k, 2])
    best = -2.0
    f = 0
    for q in range(nf[s]):
        a = normals[s, q, 0] * dl0 + normals[s, q, 1] * dl1 + normals[s, q, 2] * dl2
        if a > best:
            best = a
            f = q
    r0, r1, r2 = c[k, 0] - pos[b, 0], c[k, 1] - pos[b, 1], c[k, 2] - pos[b, 2]
    cl0 = rot[b, 0, 0] * r0 + rot[b, 1, 0] * r1 + rot[b, 2, 0] * r2  # R^T (c - x)
    cl1 = rot[b, 0, 1] * r0 + rot[b, 1, 1] * r1 + rot[b, 2, 1] * r2
    cl2 = rot[b, 0, 2] * r0 + rot[b, 1, 2] * r1 + rot[b, 2, 2] * r2
    return best, -(normals[s, f, 0] * cl0 + normals[s, f, 1] * cl1 + normals[s, f, 2] * cl2 + offsets[s, f])


@njit(cache=True, _nrt=False)
def normal_energy(kn, vol, c, n, k, normals, offsets, nf, rot, pos, sa, ba, sb, bb):
    """Elastic energy (J) of contact k's normal spring, K_n V e (module docstring): kn
    N/m^3, vol m^3, c (m, 3) the overlaps' centroids, n (m, 3) the unit normals from A to
    B; its shapes sa (of body ba) and sb (of body bb) with their face planes ``normals``
    (ns, F, 3), ``offsets`` (ns, F) (N . x + D <= 0 in their bodies' frames), ``nf``
    (ns,); ``rot`` (nb, 3, 3), ``pos`` (nb, 3) the bodies'. e is the distance of c from the
    face the overlap presses into: A's face whose outward normal is closest to n, or B's
    closest to -n, whichever is closer in direction."""
    sa_, ea = _face_depth(normals, offsets, nf, rot, pos, sa, ba, c, n, k, 1.0)
    sb_, eb = _face_depth(normals, offsets, nf, rot, pos, sb, bb, c, n, k, -1.0)
    e = ea if sa_ >= sb_ else eb
    return kn * vol * max(e, 0.0)


def normal_energies(kn, vol, c, n, Na, Da, Nb, Db, Ra, Rb, xa, xb) -> np.ndarray:
    """``normal_energy`` of m contacts in numpy (the reference): Na, Nb (m, F, 3) and Da, Db
    (m, F) each contact's two shapes' face planes in their bodies' frames (padded with zero
    normals), Ra, Rb (m, 3, 3), xa, xb (m, 3); (m,) J."""
    k = np.arange(len(vol))

    def face(N, D, R, x, d):
        al = np.einsum("kfi,kji,kj->kf", N, R, d)  # N . R^T d
        f = np.argmax(al, axis=1)
        cl = np.einsum("kji,kj->ki", R, c - x)
        return al[k, f], -(np.sum(N[k, f] * cl, axis=1) + D[k, f])

    sa, ea = face(Na, Da, Ra, xa, n)
    sb, eb = face(Nb, Db, Rb, xb, -n)
    return kn * vol * np.maximum(np.where(sa >= sb, ea, eb), 0.0)


def slip_work(f0, f_trial, f, kt, area) -> np.ndarray:
    """Plastic work of Coulomb slip (J) of m contacts over one step (module docstring):
    (f0 + f) . (f_trial - f) / (2 K_t A); f0 the previous shear force carried into the
    plane, f_trial the elastic trial, f the capped force (m, 3) N; kt N/m^3, area m^2."""
    ka = np.asarray(kt, float) * np.asarray(area, float)
    w = np.sum((f0 + f) * (f_trial - f), axis=1)
    return np.divide(w, 2.0 * ka, out=np.zeros_like(w), where=ka > 0)


class Ledger:
    """The accumulators of an engine whose integrator is not ours (YADE's NewtonIntegrator
    moves the bodies): step n's forces are kept (``begin``) until the velocities after it
    are known (``complete``, at the next step or at the run's end)."""

    def __init__(self, mass, lin_free):
        self.mass = np.where(np.isfinite(mass), mass, 1.0)
        self.moving = np.isfinite(np.asarray(mass, float))
        self.lin_free = np.asarray(lin_free, float)
        self.acc = np.zeros(3)
        self._pending = None

    @property
    def pending(self) -> bool:
        """A step's forces wait for the velocities after it."""
        return self._pending is not None

    def begin(self, dt, g, F, T, Fd, Td, F_ext, vel, angvel, slip_J, T_ext=None):
        """Step n's forces (arrays (nb, 3), as ``account``; F_ext the applied forces, the
        loads' included, T_ext (nb, 3) N m the loads' moments or None), the velocities before
        it and its slip work (J): half of it now."""
        self.acc[2] += 0.5 * slip_J
        self._pending = (dt, np.asarray(g, float), F, T, Fd, Td, F_ext, vel.copy(), angvel.copy(), 0.5 * slip_J, T_ext)

    def complete(self, vel, angvel):
        """The velocities after the pending step: its work and dissipation are added."""
        if self._pending is None:
            return
        dt, g, F, T, Fd, Td, F_ext, v0, w0, half, T_ext = self._pending
        account(dt, g, F, T, Fd, Td, F_ext, self.moving, self.mass, self.lin_free, v0, w0, vel, angvel, half, self.acc)
        if T_ext is not None:  # the moments' work M . w_bar dt (blocked rotations keep w = 0)
            w_bar = 0.5 * (w0 + angvel)
            self.acc[0] += dt * float(np.sum(T_ext[self.moving] * w_bar[self.moving]))
        self._pending = None

    def add_work(self, J: float) -> None:
        """Work of a load given at once (a velocity jump's kinetic energy), J."""
        self.acc[0] += float(J)
