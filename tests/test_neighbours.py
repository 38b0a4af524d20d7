"""The contact search's neighbour list (drystone/mechanics/neighbours.py) against the full
search it spares (``overlap.contacts_of_shapes``), no YADE: along a seeded random motion
of a running-bond wall (translations and rotations, some steps larger than the skin) the
listed search gives the full search's contacts, in its order, bit for bit (the same
arithmetic on the same pairs: equal by construction), while rebuilding the list only
when a body moved by more than half the skin; a stone taken out (non-finite vertices,
``invalidate``) leaves every contact at once.
"""
import numpy as np

from drystone.geometry import polyhedron as ph
from drystone.geometry import running_bond
from drystone.mechanics import neighbours as nbr
from drystone.mechanics import overlap as ov
from drystone.mechanics import rotations


def _wall():
    blocks = running_bond.make(courses=3, per_course=4, length=4.0, height=1.5, thickness=0.5)["blocks"]
    verts = [np.asarray(b["vertices"], float) for b in blocks]
    cen = np.array([ph.volume_centroid(v)[1] for v in verts])
    moving = np.array([b["role"] == "free" for b in blocks])
    pos = cen.copy()
    pos[moving, 2] -= 2e-4  # pressed into the joints: contacts
    return ov.Shapes([v - c for v, c in zip(verts, cen)]), pos, moving


def _compare(s, owner, moving, L, pos, rot):
    full = ov.contacts_of_shapes(s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, owner, pos, rot, moving,
                                 ov.TOL)
    L.arrays = nbr.update(L.arrays, s.verts, s.nv, s.normals, s.offsets, s.nf, owner, pos, rot, 1)
    m, L.contacts = nbr.search(L.arrays, L.contacts, s.nv, s.nf, s.faces, s.fk, ov.TOL, ov.TOUCHING_IS_NO_CONTACT)
    assert m == len(full[0])
    for a, b in zip(full, L.contacts[:8]):
        assert np.array_equal(a, b[:m])
    return m


def test_listed_search_is_the_full_search_bit_for_bit():
    s, pos, moving = _wall()
    nb = len(pos)
    owner = np.arange(nb)
    skin = 0.01
    L = nbr.NeighbourList(s, owner, moving, nb, skin)
    rng = np.random.default_rng(3)
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (nb, 1))
    contacts = []
    steps = 60
    for k in range(steps):
        # mostly small steps (no rebuild), every 15th a jump of about the skin
        scale = skin if k % 15 == 14 else 2e-4
        pos[moving] += scale * rng.standard_normal((moving.sum(), 3))
        quat[moving, :3] += 0.2 * scale * rng.standard_normal((moving.sum(), 3))
        quat /= np.linalg.norm(quat, axis=1)[:, None]
        contacts.append(_compare(s, owner, moving, L, pos, rotations.to_matrix(quat)))
    assert max(contacts) > 0
    assert 2 <= L.builds < steps // 3


def test_stale_bound():
    """A body rotated by theta about its origin moves its farthest vertex (radius r) by the
    chord 2 r sin(theta / 2): the rebuild rule's bound must not be below it."""
    r = np.array([0.5])
    for theta in (1e-6, 0.01, 0.3, 3.0):
        c, si = np.cos(theta), np.sin(theta)
        rot = np.array([[[c, -si, 0.0], [si, c, 0.0], [0.0, 0.0, 1.0]]])
        chord = 2.0 * r[0] * np.sin(0.5 * theta)
        assert nbr._stale(np.zeros((1, 3)), rot, np.zeros((1, 3)), np.eye(3)[None], r, 0.999 * chord)
    assert not nbr._stale(np.full((1, 3), 1e-3), np.eye(3)[None], np.zeros((1, 3)), np.eye(3)[None], r, 2e-3)
    assert nbr._stale(np.full((1, 3), np.nan), np.eye(3)[None], np.zeros((1, 3)), np.eye(3)[None], r, 2e-3)


def test_a_stone_taken_out_has_no_contact():
    s, pos, moving = _wall()
    nb = len(pos)
    owner = np.arange(nb)
    rot = np.tile(np.eye(3), (nb, 1, 1))
    L = nbr.NeighbourList(s, owner, moving, nb)
    m = _compare(s, owner, moving, L, pos, rot)
    out = int(np.flatnonzero(moving)[0])
    before = L.contacts[0][:m].tolist() + L.contacts[1][:m].tolist()
    assert out in before
    builds = L.builds
    s.verts[owner == out] = np.nan
    L.invalidate()
    m = _compare(s, owner, moving, L, pos, rot)
    assert L.builds == builds + 1
    assert out not in L.contacts[0][:m].tolist() + L.contacts[1][:m].tolist()
    assert out not in L.arrays[0][:len(L)].tolist() + L.arrays[1][:len(L)].tolist()
