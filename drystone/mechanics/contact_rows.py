"""The compiled step's work per contact and per body, on numba's threads (no YADE import).

``contact_step._advance`` finds a step's contacts (``drystone.mechanics.neighbours``)
and then calls, in this order:

* ``law_rows``: each contact's joint properties, its history of the previous step, the
  penalty-Coulomb shear spring, the twist spring and the levers and relative twist that
  the damping takes (``drystone.mechanics.contact``), with both bodies' inverse inertia
  in the global frame;
* ``body_sums``: the contact forces and torques, and the damping's alone, summed on every
  body;
* ``elastic_energy``: the energy stored in the contacts' springs
  (``drystone.mechanics.energy``), only at the steps that record it.

Threads and round-off. Each contact's arithmetic is written into its own row (the slip
work's and the elastic energy's terms too), independent of the thread that does it; the
sums that mix contacts are then taken in the contacts' order: the energies by one thread,
the forces by body, each body adding its own contacts' terms in the contacts' order (a
list of them per body, built every step). Every body therefore receives the same terms in
the same order as when one loop over the contacts added each contact's terms to its two
bodies, and every number is the same bit for bit for any number of threads.

Units SI; the contacts' forces act on body B (``ob``), their opposites on A (``oa``).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from drystone.mechanics import contact as law
from drystone.mechanics import energy
from drystone import numba_cache
from drystone.numba_cache import FIRST, PARALLEL

numba_cache.install()  # numba's cache safe for processes compiling at once

#: fewer rows than this (contacts, bodies, shapes) are done on the calling thread: starting
#: the threads' loop costs microseconds (3.5 us on one thread, ~30 us on two of a busy
#: machine), more than a few hundred rows of work on a small wall
PARALLEL_ROWS = 256


@njit(cache=True)
def range_count(rows, chunks):
    """Ranges to cut ``rows`` rows into: ``chunks`` (one per thread numba may run, as the
    caller passes it), 1 (the calling thread) below PARALLEL_ROWS rows. A kernel loops over
    its rows within a range: one call per range, not per row (a call of a kernel with many
    array arguments costs a reference count per array, which outweighed a contact's law).
    The kernels called per row allocate nothing and are compiled without reference counts
    (``_nrt=False``; ``drystone.mechanics.overlap``, "Reference counts")."""
    return max(1, chunks) if rows >= PARALLEL_ROWS else 1

@njit(cache=True, _nrt=False)
def _global_inverse(R, d, out):
    """out = R diag(d) R^T: a body's inverse inertia in the global frame."""
    for i in range(3):
        for j in range(3):
            out[i, j] = R[i, 0] * d[0] * R[j, 0] + R[i, 1] * d[1] * R[j, 1] + R[i, 2] * d[2] * R[j, 2]


@njit(cache=True, _nrt=False)
def _props(a, b, nb, mat, table, jkeys, jvals, k, kn, kt, mu, xi):
    """kn, kt, mu, damping of contact k between bodies a and b into its rows: the material
    pair's, or the joint's override (jkeys: sorted a * nb + b of the overridden pairs of
    bodies, a < b)."""
    key = min(a, b) * nb + max(a, b)
    j = np.searchsorted(jkeys, key)
    if j < len(jkeys) and jkeys[j] == key:
        p = jvals[j]
    else:
        p = table[mat[a], mat[b]]
    kn[k] = p[0]
    kt[k] = p[1]
    mu[k] = p[2]
    xi[k] = p[3]


@njit(cache=True, _nrt=False)
def _law_range(r0, r1, oa, ob, c, n, area, pc, pj, vol, pos, vel, angvel, rot, inv_inertia_local, mat, table, jkeys,
               jvals, prev, prev_shear, prev_basis, dt, kn, kt, mu, xi, fn, fs, basis, jp, slipping, ra, rb, pa, pb,
               lever, twist, iia, iib, slip_terms):
    """Contacts r0 <= k < r1 of ``law_rows``."""
    for k in range(r0, r1):
        nb = len(pos)
        ncol = fs.shape[1]
        scaled = ncol >= 6
        a = oa[k]
        b = ob[k]
        _props(a, b, nb, mat, table, jkeys, jvals, k, kn, kt, mu, xi)
        fn[k] = kn[k] * vol[k]
        j = prev[k]
        for q in range(ncol):
            fs[k, q] = 0.0
        if j >= 0:
            for r in range(6):
                for u in range(6):
                    basis[k, r, u] = prev_basis[j, r, u]
            h0, h1, h2, h3 = prev_shear[j, 0], prev_shear[j, 1], prev_shear[j, 2], prev_shear[j, 3]
            h4 = prev_shear[j, 4] if scaled else 0.0
            h5 = prev_shear[j, 5] if scaled else 0.0
        else:
            for r in range(6):
                for u in range(6):
                    basis[k, r, u] = 0.0
            h0 = h1 = h2 = h3 = h4 = h5 = 0.0
        _global_inverse(rot[a], inv_inertia_local[a], iia[k])
        _global_inverse(rot[b], inv_inertia_local[b], iib[k])
        n0, n1, n2 = n[k, 0], n[k, 1], n[k, 2]
        for q in range(3):
            ra[k, q] = c[k, q] - pos[a, q]
            rb[k, q] = c[k, q] - pos[b, q]
            pa[k, q] = pc[k, q] - pos[a, q]
            pb[k, q] = pc[k, q] - pos[b, q]
            lever[k, q] = c[k, q] - pc[k, q]
        # shear spring at the overlap centroid (contact.shear_spring); B's velocity
        # relative to A there: (v_b + w_b x r_b) - (v_a + w_a x r_a)
        vr0 = (vel[b, 0] + (angvel[b, 1] * rb[k, 2] - angvel[b, 2] * rb[k, 1])) \
            - (vel[a, 0] + (angvel[a, 1] * ra[k, 2] - angvel[a, 2] * ra[k, 1]))
        vr1 = (vel[b, 1] + (angvel[b, 2] * rb[k, 0] - angvel[b, 0] * rb[k, 2])) \
            - (vel[a, 1] + (angvel[a, 2] * ra[k, 0] - angvel[a, 0] * ra[k, 2]))
        vr2 = (vel[b, 2] + (angvel[b, 0] * rb[k, 1] - angvel[b, 1] * rb[k, 0])) \
            - (vel[a, 2] + (angvel[a, 0] * ra[k, 1] - angvel[a, 1] * ra[k, 0]))
        vn = vr0 * n0 + vr1 * n1 + vr2 * n2
        mag = np.sqrt(h0 ** 2 + h1 ** 2 + h2 ** 2)
        f0n = h0 * n0 + h1 * n1 + h2 * n2
        p0 = h0 - f0n * n0
        p1 = h1 - f0n * n1
        p2 = h2 - f0n * n2
        pm = np.sqrt(p0 ** 2 + p1 ** 2 + p2 ** 2)
        sc = mag / pm if pm > 0.0 else 0.0
        kta = kt[k] * area[k]
        jp[k] = law.polar_moment(n[k], pj[k])
        e_area = 0.0
        e_polar = 0.0
        if scaled:  # the part of the carried force and moment the patch's springs still hold
            r, e_area = law.carried_share(h4, area[k], mag * mag, kt[k], ncol > 6)
            sc *= r
            rj, e_polar = law.carried_share(h5, jp[k], h3 * h3, kt[k], ncol > 6)
            h3 *= rj
            fs[k, 4] = area[k]
            fs[k, 5] = jp[k]
        slip_terms[k, 0] = e_area
        slip_terms[k, 1] = e_polar
        fs[k, 0] = p0 * sc - kta * (vr0 - vn * n0) * dt
        fs[k, 1] = p1 * sc - kta * (vr1 - vn * n1) * dt
        fs[k, 2] = p2 * sc - kta * (vr2 - vn * n2) * dt
        fm = np.sqrt(fs[k, 0] ** 2 + fs[k, 1] ** 2 + fs[k, 2] ** 2)
        fmax = mu[k] * fn[k]
        slipping[k] = False
        slip_terms[k, 2] = 0.0
        if fm > fmax:
            slipping[k] = True
            s = fmax / fm
            # the return mapping's plastic work (energy.slip_work): (f0 + f) . (f* - f) / (2 K_t A)
            # with f = s f*: (1 - s) (f0 . f* + s |f*|^2)
            if kta > 0.0:
                f0t = p0 * sc * fs[k, 0] + p1 * sc * fs[k, 1] + p2 * sc * fs[k, 2]
                slip_terms[k, 2] = (1.0 - s) * (f0t + s * fm * fm) / (2.0 * kta)
            for q in range(3):
                fs[k, q] *= s
        # the twist spring on the patch (contact.twist_spring)
        wn = (angvel[b, 0] - angvel[a, 0]) * n0 + (angvel[b, 1] - angvel[a, 1]) * n1 \
            + (angvel[b, 2] - angvel[a, 2]) * n2
        fs[k, 3], slip_terms[k, 3] = law.twist_spring(h3, wn, jp[k], area[k], kt[k], mu[k], fn[k],
                                                      np.sqrt(fs[k, 0] ** 2 + fs[k, 1] ** 2 + fs[k, 2] ** 2), dt)
        # relative twist at the patch centroid
        twist[k, 0] = (vel[b, 0] + (angvel[b, 1] * pb[k, 2] - angvel[b, 2] * pb[k, 1])) \
            - (vel[a, 0] + (angvel[a, 1] * pa[k, 2] - angvel[a, 2] * pa[k, 1]))
        twist[k, 1] = (vel[b, 1] + (angvel[b, 2] * pb[k, 0] - angvel[b, 0] * pb[k, 2])) \
            - (vel[a, 1] + (angvel[a, 2] * pa[k, 0] - angvel[a, 0] * pa[k, 2]))
        twist[k, 2] = (vel[b, 2] + (angvel[b, 0] * pb[k, 1] - angvel[b, 1] * pb[k, 0])) \
            - (vel[a, 2] + (angvel[a, 0] * pa[k, 1] - angvel[a, 1] * pa[k, 0]))
        for q in range(3):
            twist[k, 3 + q] = angvel[b, q] - angvel[a, q]


@njit(cache=True, parallel=PARALLEL)
def law_rows(oa, ob, c, n, area, pc, pj, vol, pos, vel, angvel, rot, inv_inertia_local, mat, table, jkeys, jvals,
             prev, prev_shear, prev_basis, dt, kn, kt, mu, xi, fn, fs, basis, jp, slipping, ra, rb, pa, pb, lever,
             twist, iia, iib, slip_terms, chunks):
    """Each contact k (between bodies oa[k] and ob[k]; overlap centroid c, normal n, area,
    patch centroid pc and second moment pj, volume vol) into its rows: its properties kn,
    kt, mu, xi and elastic normal force fn = kn vol; its history (``prev[k]``: its row in
    the previous step's ``prev_shear``, ``prev_basis``, or -1 for a new contact) carried into
    ``fs`` (shear force, twisting moment, and with 6 columns the area and polar moment at
    the step: the carried force scaled by the patch, contact.carried_share) and ``basis``
    (the damping's modes; zeros for a new contact); the shear and twist springs of this
    step (``slipping``); the levers ra, rb (overlap centroid) and pa, pb (patch centroid)
    from the bodies' centres, ``lever`` = c - pc, the relative twist of B with respect to
    A at the patch centroid, the bodies' inverse inertia in the global frame iia, iib; the
    slip work's terms (J) in ``slip_terms`` (m, 4): the two carried shares' drops, the
    shear spring's return mapping and the twist spring's cap, to be added in that order.
    ``chunks``: ranges of contacts shared among the threads (``range_count``)."""
    m = len(oa)
    nt = range_count(m, chunks)
    if nt == 1:
        _law_range(FIRST, m, oa, ob, c, n, area, pc, pj, vol, pos, vel, angvel, rot, inv_inertia_local, mat, table,
                   jkeys, jvals, prev, prev_shear, prev_basis, dt, kn, kt, mu, xi, fn, fs, basis, jp, slipping, ra, rb, pa,
                   pb, lever, twist, iia, iib, slip_terms)
    else:
        for t in prange(nt):
            _law_range(t * m // nt, (t + 1) * m // nt, oa, ob, c, n, area, pc, pj, vol, pos, vel, angvel, rot,
                       inv_inertia_local, mat, table, jkeys, jvals, prev, prev_shear, prev_basis, dt, kn, kt, mu, xi,
                       fn, fs, basis, jp, slipping, ra, rb, pa, pb, lever, twist, iia, iib, slip_terms)


@njit(cache=True)
def slip_work(slip_terms):
    """The step's slip work (J): every contact's terms added in the contacts' order (a
    term that is zero, where a contact has none, leaves the sum as it is)."""
    slip = 0.0
    for k in range(slip_terms.shape[0]):
        for q in range(4):
            slip += slip_terms[k, q]
    return slip


@njit(cache=True)
def _by_body(oa, ob, nb):
    """Each body's contacts in the contacts' order: (start (nb + 1,), entries): body i's are
    entries[start[i]:start[i + 1]], 2 k for contact k acting on it as B, 2 k + 1 as A (B
    first within a contact)."""
    m = len(oa)
    start = np.zeros(nb + 1, np.int64)
    for k in range(m):
        start[ob[k] + 1] += 1
        start[oa[k] + 1] += 1
    for i in range(nb):
        start[i + 1] += start[i]
    fill = start[:nb].copy()
    entries = np.empty(2 * m, np.int64)
    for k in range(m):
        entries[fill[ob[k]]] = 2 * k
        fill[ob[k]] += 1
        entries[fill[oa[k]]] = 2 * k + 1
        fill[oa[k]] += 1
    return start, entries


@njit(cache=True, _nrt=False)
def _wrench_terms(k, on_a, fs, fn, n, fd, md, ra, rb, pa, pb, out):
    """Contact k's terms on one of its bodies into out (4, 3): the force on B (elastic
    normal + shear spring + damping) and the damping's, and the torques about the body's
    centre (``on_a``: A's, else B's) of all of it and of the damping alone (r x f_c at the
    overlap centroid, p x f_d at the patch centroid, + m_d, + the twisting moment M_t n).
    A subtracts them, B adds them."""
    fc0 = fs[k, 0] + fn[k] * n[k, 0]
    fc1 = fs[k, 1] + fn[k] * n[k, 1]
    fc2 = fs[k, 2] + fn[k] * n[k, 2]
    d0, d1, d2 = fd[k, 0], fd[k, 1], fd[k, 2]
    out[0, 0] = fc0 + d0
    out[0, 1] = fc1 + d1
    out[0, 2] = fc2 + d2
    out[1, 0] = d0
    out[1, 1] = d1
    out[1, 2] = d2
    r = ra if on_a else rb
    p = pa if on_a else pb
    out[2, 0] = (r[k, 1] * fc2 - r[k, 2] * fc1) + (p[k, 1] * d2 - p[k, 2] * d1) + md[k, 0] + fs[k, 3] * n[k, 0]
    out[2, 1] = (r[k, 2] * fc0 - r[k, 0] * fc2) + (p[k, 2] * d0 - p[k, 0] * d2) + md[k, 1] + fs[k, 3] * n[k, 1]
    out[2, 2] = (r[k, 0] * fc1 - r[k, 1] * fc0) + (p[k, 0] * d1 - p[k, 1] * d0) + md[k, 2] + fs[k, 3] * n[k, 2]
    out[3, 0] = (p[k, 1] * d2 - p[k, 2] * d1) + md[k, 0]
    out[3, 1] = (p[k, 2] * d0 - p[k, 0] * d2) + md[k, 1]
    out[3, 2] = (p[k, 0] * d1 - p[k, 1] * d0) + md[k, 2]


@njit(cache=True)
def _body_range(r0, r1, start, entries, fs, fn, n, fd, md, ra, rb, pa, pb, F, T, Fd, Td):
    """Bodies r0 <= i < r1 of ``_add_by_body``."""
    w = np.empty((4, 3))
    for i in range(r0, r1):
        for e in range(start[i], start[i + 1]):
            k = entries[e] >> 1
            on_a = (entries[e] & 1) == 1
            _wrench_terms(k, on_a, fs, fn, n, fd, md, ra, rb, pa, pb, w)
            if on_a:
                for q in range(3):
                    F[i, q] -= w[0, q]
                    T[i, q] -= w[2, q]
                    Fd[i, q] -= w[1, q]
                    Td[i, q] -= w[3, q]
            else:
                for q in range(3):
                    F[i, q] += w[0, q]
                    T[i, q] += w[2, q]
                    Fd[i, q] += w[1, q]
                    Td[i, q] += w[3, q]


@njit(cache=True, parallel=PARALLEL)
def _add_by_body(start, entries, fs, fn, n, fd, md, ra, rb, pa, pb, F, T, Fd, Td, chunks):
    """Every body's terms (``_by_body``, ``_wrench_terms``) added in its list's order."""
    nb = len(start) - 1
    nt = range_count(nb, chunks)
    if nt == 1:
        _body_range(FIRST, nb, start, entries, fs, fn, n, fd, md, ra, rb, pa, pb, F, T, Fd, Td)
    else:
        for t in prange(nt):
            _body_range(t * nb // nt, (t + 1) * nb // nt, start, entries, fs, fn, n, fd, md, ra, rb, pa, pb, F, T, Fd,
                        Td)


@njit(cache=True)
def body_sums(oa, ob, nb, fs, fn, n, fd, md, ra, rb, pa, pb, chunks):
    """(F, T, Fd, Td) (nb, 3): the contact forces and torques on every body (N, N m) and
    those of the damping alone (energy.account): each contact's force on B, fs + fn n +
    fd at its centroids, its torque about B's centre r_b x (fs + fn n) + p_b x fd + md +
    M_t n (fs[:, 3] the twisting moment M_t), and their opposites on A."""
    start, entries = _by_body(oa, ob, nb)
    F = np.zeros((nb, 3))
    T = np.zeros((nb, 3))
    Fd = np.zeros((nb, 3))
    Td = np.zeros((nb, 3))
    _add_by_body(start, entries, fs, fn, n, fd, md, ra, rb, pa, pb, F, T, Fd, Td, chunks)
    return F, T, Fd, Td


@njit(cache=True, _nrt=False)
def _energy_range(r0, r1, ia, ib, oa, ob, kn, kt, vol, c, n, area, fs, jp, normals, offsets, nf, rot, pos, e):
    """Each contact's elastic energy (J), contacts r0 <= k < r1: its normal and shear
    springs' (e[k, 0]) and its twist spring's (e[k, 1]); zeros for a contact without area."""
    for k in range(r0, r1):
        e[k, 0] = 0.0
        e[k, 1] = 0.0
        if area[k] > 0.0:
            e[k, 0] = energy.normal_energy(kn[k], vol[k], c, n, k, normals, offsets, nf, rot, pos, ia[k], oa[k], ib[k],
                                           ob[k]) + (fs[k, 0] ** 2 + fs[k, 1] ** 2 + fs[k, 2] ** 2) / (
                                               2.0 * kt[k] * area[k])
            if kt[k] * jp[k] > 0.0:
                e[k, 1] = fs[k, 3] ** 2 / (2.0 * kt[k] * jp[k])


@njit(cache=True)
def elastic_energy(ia, ib, oa, ob, kn, kt, vol, c, n, area, fs, jp, normals, offsets, nf, rot, pos):
    """The elastic energy stored in the contacts (J; energy.normal_energy, the shear spring's
    |F_t|^2 / (2 K_t A) and the twist spring's M_t^2 / (2 K_t J_p)), added in the contacts'
    order. Contacts ia, ib (shapes) of bodies oa, ob. On the calling thread: it is summed
    at the recorded steps only (a kernel fewer to compile)."""
    e = np.empty((len(ia), 2))
    _energy_range(0, len(ia), ia, ib, oa, ob, kn, kt, vol, c, n, area, fs, jp, normals, offsets, nf, rot, pos, e)
    total = 0.0
    for k in range(len(ia)):
        if area[k] > 0.0:
            total += e[k, 0]
            if kt[k] * jp[k] > 0.0:
                total += e[k, 1]
    return total
