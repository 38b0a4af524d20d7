"""The motion of rigid bodies over arrays (numba, no YADE import): ``integrate`` advances
every body one leapfrog step the way YADE's NewtonIntegrator (2023.02a) does, so that the
state can stay in arrays between steps (the compiled engine, drystone/yade_scripts/
engines.py; ``contact_step.CompiledStep.advance`` calls it between contact steps):
translation v += dt (F/m + g), x += v dt on the free directions; rotation with Fincham's
(1992) angular-momentum scheme for bodies free to rotate about all three axes (YADE's
``exactAsphericalRot``), and with the spherical update w += dt M / I (global components)
for bodies with a blocked rotation, as YADE does. ``free_directions`` reads YADE's
blockedDOFs; ``matrices`` gives rotation matrices of quaternions.

Units SI; quaternions (x, y, z, w) like YADE's; body arrays indexed by YADE body id.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from drystone.mechanics import rotations
from drystone.mechanics.contact_rows import range_count
from drystone import numba_cache
from drystone.numba_cache import FIRST, PARALLEL

numba_cache.install()  # numba's cache safe for processes compiling at once


@njit(cache=True, _nrt=False)
def _quat_matrix(q, R):
    """R = rotation matrix of the unit quaternion q (x, y, z, w), the same arithmetic as
    ``rotations.to_matrix`` (touching faces make contacts sensitive to its round-off)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    R[0, 0] = 1 - 2 * (y * y + z * z)
    R[0, 1] = 2 * (x * y - z * w)
    R[0, 2] = 2 * (x * z + y * w)
    R[1, 0] = 2 * (x * y + z * w)
    R[1, 1] = 1 - 2 * (x * x + z * z)
    R[1, 2] = 2 * (y * z - x * w)
    R[2, 0] = 2 * (x * z - y * w)
    R[2, 1] = 2 * (y * z + x * w)
    R[2, 2] = 1 - 2 * (x * x + y * y)


@njit(cache=True, _nrt=False)
def _eigen_matrix(q, R):
    """R = rotation matrix of q (x, y, z, w) as Eigen computes it (YADE's ``A`` in the
    aspherical integration)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    R[0, 0] = 1.0 - (tyy + tzz)
    R[0, 1] = txy - twz
    R[0, 2] = txz + twy
    R[1, 0] = txy + twz
    R[1, 1] = 1.0 - (txx + tzz)
    R[1, 2] = tyz - twx
    R[2, 0] = txz - twy
    R[2, 1] = tyz + twx
    R[2, 2] = 1.0 - (txx + tyy)


@njit(cache=True, _nrt=False)
def _dot_q(w, q, out):
    """dQ/dt into ``out`` (4,) for the body-frame angular velocity w at orientation q (x, y, z, w)."""
    out[3] = (-q[0] * w[0] - q[1] * w[1] - q[2] * w[2]) / 2.0
    out[0] = (q[3] * w[0] - q[2] * w[1] + q[1] * w[2]) / 2.0
    out[1] = (q[2] * w[0] + q[3] * w[1] - q[0] * w[2]) / 2.0
    out[2] = (-q[1] * w[0] + q[0] * w[1] + q[3] * w[2]) / 2.0


@njit(cache=True, _nrt=False)
def _to_body(A, x, inertia, out):
    """out = (A x) / inertia, elementwise (3,): A x row by row, left to right, as Eigen's
    3 x 3 product without fused multiply-adds (numpy's ``@`` calls BLAS, whose order and
    FMAs differ in the last bit)."""
    for a in range(3):
        out[a] = (A[a, 0] * x[0] + A[a, 1] * x[1] + A[a, 2] * x[2]) / inertia[a]


@njit(cache=True, _nrt=False)
def _normalise(q):
    """q /= |q|, summing the squares in the order of Eigen's vectorised norm (YADE)."""
    s = np.sqrt((q[0] * q[0] + q[2] * q[2]) + (q[1] * q[1] + q[3] * q[3]))
    for i in range(4):
        q[i] /= s


@njit(cache=True)
def _integrate_range(r0, r1, dt, g, F, T, mass, inertia, lin_free, rot_free, aspherical, pos, vel, angvel, angmom, quat,
                     rot):
    """Bodies r0 <= i < r1 of ``integrate``."""
    # work arrays, once per call (no allocation per body)
    A = np.empty((3, 3))
    conj = np.empty(4)
    ln = np.empty(3)
    wv = np.empty(3)
    dq = np.empty(4)
    qh = np.empty(4)
    qn = np.empty(4)
    for i in range(r0, r1):
        for a in range(3):
            if lin_free[i, a] > 0.0:
                vel[i, a] += dt * (F[i, a] / mass[i] + g[a])
            pos[i, a] += vel[i, a] * dt
        q = quat[i]
        if aspherical[i]:
            conj[0], conj[1], conj[2], conj[3] = -q[0], -q[1], -q[2], q[3]
            _eigen_matrix(conj, A)  # global -> body
            M = T[i]
            for a in range(3):
                ln[a] = angmom[i, a] + dt / 2.0 * M[a]
            _to_body(A, ln, inertia[i], wv)  # body-frame angular velocity at the half step
            _dot_q(wv, q, dq)
            for a in range(4):
                qh[a] = q[a] + dt / 2.0 * dq[a]
            for a in range(3):
                angmom[i, a] += dt * M[a]
            _to_body(A, angmom[i], inertia[i], wv)  # ... and at the step's end
            _dot_q(wv, qh, dq)
            for a in range(4):
                qn[a] = q[a] + dt * dq[a]
            # angVel = qn * wh (Eigen's quaternion-vector product on the unnormalised qn):
            # uv = 2 u x wh, w = wh + qn_w uv + u x uv
            u0, u1, u2, w0, w1, w2 = qn[0], qn[1], qn[2], wv[0], wv[1], wv[2]
            c0 = u1 * w2 - u2 * w1
            c1 = u2 * w0 - u0 * w2
            c2 = u0 * w1 - u1 * w0
            c0, c1, c2 = c0 + c0, c1 + c1, c2 + c2
            angvel[i, 0] = w0 + qn[3] * c0 + (u1 * c2 - u2 * c1)
            angvel[i, 1] = w1 + qn[3] * c1 + (u2 * c0 - u0 * c2)
            angvel[i, 2] = w2 + qn[3] * c2 + (u0 * c1 - u1 * c0)
            _normalise(qn)
            for a in range(4):
                quat[i, a] = qn[a]
        else:
            for a in range(3):
                if rot_free[i, a] > 0.0:
                    angvel[i, a] += dt * T[i, a] / inertia[i, a]
            w2 = angvel[i, 0] ** 2 + angvel[i, 1] ** 2 + angvel[i, 2] ** 2
            if w2 != 0.0:
                ang = np.sqrt(w2)
                h = (ang * dt) * 0.5
                s = np.sin(h)
                r0, r1, r2, r3 = s * (angvel[i, 0] / ang), s * (angvel[i, 1] / ang), s * (angvel[i, 2] / ang), np.cos(h)
                x0 = r3 * q[0] + r0 * q[3] + r1 * q[2] - r2 * q[1]
                x1 = r3 * q[1] + r1 * q[3] + r2 * q[0] - r0 * q[2]
                x2 = r3 * q[2] + r2 * q[3] + r0 * q[1] - r1 * q[0]
                x3 = r3 * q[3] - r0 * q[0] - r1 * q[1] - r2 * q[2]
                quat[i, 0], quat[i, 1], quat[i, 2], quat[i, 3] = x0, x1, x2, x3
                _normalise(quat[i])
            elif not lin_free[i].any() and not rot_free[i].any():
                continue  # a non-moving body that does not turn keeps its orientation as given
            else:
                _normalise(quat[i])
        _quat_matrix(quat[i], rot[i])


@njit(cache=True, parallel=PARALLEL)
def integrate(dt, g, F, T, mass, inertia, lin_free, rot_free, aspherical, pos, vel, angvel, angmom, quat, rot, chunks):
    """One leapfrog step of every body, in place (module docstring). ``g`` (3,) body
    acceleration m/s^2; F, T (nb, 3) N, N m; lin_free, rot_free (nb, 3) 1.0 on free
    directions (all 0 for non-moving bodies, which still move with their velocity);
    aspherical (nb,) bool: Fincham's scheme (all rotations free). ``rot`` is refreshed.
    ``chunks``: ranges of bodies shared among numba's threads (each body's arithmetic on
    its own: the same numbers for any count; ``contact_rows.range_count``)."""
    nb = len(mass)
    nt = range_count(nb, chunks)
    if nt == 1:
        _integrate_range(FIRST, nb, dt, g, F, T, mass, inertia, lin_free, rot_free, aspherical, pos, vel, angvel,
                         angmom, quat, rot)
    else:
        for t in prange(nt):
            _integrate_range(t * nb // nt, (t + 1) * nb // nt, dt, g, F, T, mass, inertia, lin_free, rot_free,
                             aspherical, pos, vel, angvel, angmom, quat, rot)


def free_directions(blocked: str, moving: bool) -> tuple[np.ndarray, np.ndarray]:
    """(translation, rotation) masks (3,) of 1.0 on the directions a body may use, from
    YADE's ``blockedDOFs`` letters (x y z translations, X Y Z rotations)."""
    if not moving:
        return np.zeros(3), np.zeros(3)
    blocked = blocked or ""
    return (np.array([0.0 if c in blocked else 1.0 for c in "xyz"]),
            np.array([0.0 if c in blocked else 1.0 for c in "XYZ"]))


def matrices(quat) -> np.ndarray:
    """Rotation matrices of (nb, 4) quaternions (``drystone.mechanics.rotations``)."""
    return rotations.to_matrix(quat)
