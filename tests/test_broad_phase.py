"""The contact search's broad phase (drystone/mechanics/overlap.py: sort and sweep on the bounding
boxes) against the all-pairs search it replaced: the same candidates, the same contacts
bit for bit; and the touching rule (pairs touching within TOL are no contact)."""
import numpy as np
import pytest

import tolerances as tol
from drystone.mechanics import overlap as ov


def _rotation(rng, angle):
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def packing(seed, shape=(6, 3, 4), cell=(0.6, 0.5, 0.3)):
    """Boxes on a grid of ``shape`` cells: a third exactly the cell (touching their
    neighbours face to face), a third larger by up to 2 mm (overlapping), a third smaller
    (apart); a third of them turned by up to 5 mrad; a fifth not moving; body numbers
    shuffled. Returns the arguments of ``contacts_with_patches``."""
    rng = np.random.default_rng(seed)
    cell = np.asarray(cell)
    local, pos, rot = [], [], []
    for idx in np.ndindex(*shape):
        kind = rng.integers(3)
        size = cell + (0.0 if kind == 0 else rng.uniform(0, 2e-3, 3) if kind == 1 else -rng.uniform(0, 2e-3, 3))
        h = size / 2
        local.append(np.array([[x, y, z] for x in (-h[0], h[0]) for y in (-h[1], h[1]) for z in (-h[2], h[2])]))
        pos.append((np.array(idx) + 0.5) * cell)
        rot.append(_rotation(rng, rng.uniform(0, 5e-3)) if rng.uniform() < 1 / 3 else np.eye(3))
    order = rng.permutation(len(local))
    local = [local[k] for k in order]
    s = ov.Shapes(local)
    moving = rng.uniform(size=len(local)) >= 0.2
    return (s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, np.array(pos)[order], np.array(rot)[order],
            moving, ov.TOL)


def _global(args):
    verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol = args
    return ov._global_geometry(verts, nv, normals, offsets, nf, pos, rot)


def _brute_candidates(lo, hi, moving):
    nb = len(lo)
    return {(i, j) for i in range(nb) for j in range(i + 1, nb)
            if (moving[i] or moving[j]) and np.all(lo[i] <= hi[j]) and np.all(lo[j] <= hi[i])}


def _candidates_clipped(args, touching):
    """The sweep's candidates clipped, with or without the touching rule."""
    verts, nv, normals, offsets, nf, faces, fk, pos, rot, moving, tol = args
    GV, GN, GD, lo, hi = _global(args)
    ia, ib = ov.sweep_pairs(lo, hi, moving)
    return ov._contacts_of_pairs(GV, GN, GD, nv, nf, faces, fk, ia, ib, tol, touching)


def _apart(args, id1, id2):
    nv, nf, tol = args[1], args[4], args[10]
    GV, GN, GD, _, _ = _global(args)
    return np.array([ov._apart(GV[i], nv[i], GN[i], GD[i], nf[i], GV[j], nv[j], GN[j], GD[j], nf[j], tol)
                     for i, j in zip(id1, id2)], bool)


@pytest.mark.parametrize("seed", range(6))
def test_sweep_candidates_are_the_all_pairs_ones(seed):
    """The sweep's candidates are exactly the pairs whose closed boxes overlap (with a
    moving body), sorted, id1 < id2; they include every overlapping pair."""
    args = packing(seed)
    lo, hi = _global(args)[3:]
    moving = args[9]
    ia, ib = ov.sweep_pairs(lo, hi, moving)
    pairs = list(zip(ia.tolist(), ib.tolist()))
    assert pairs == sorted(_brute_candidates(lo, hi, moving))
    ref = ov._contacts_all_pairs(*args)
    assert len(ref[0]) > 50  # the packing has contacts to find
    assert set(zip(ref[0].tolist(), ref[1].tolist())) <= set(pairs)


@pytest.mark.parametrize("seed", range(6))
def test_contacts_equal_the_all_pairs_search(seed):
    """The sweep's candidates clipped give the all-pairs search's contacts bit for bit;
    the search (touching rule on) gives the same less the pairs touching within TOL,
    whose overlap is round-off (thinner than TOL)."""
    args = packing(seed)
    ref = ov._contacts_all_pairs(*args)
    clipped = _candidates_clipped(args, False)
    assert len(clipped) == len(ref) == 8
    for a, b in zip(clipped, ref):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    assert ov.TOUCHING_IS_NO_CONTACT
    new = ov.contacts_with_patches(*args)
    keep = ~_apart(args, ref[0], ref[1])
    for a, b in zip(new, ref):
        assert a.dtype == b.dtype and np.array_equal(a, b[keep])
    assert np.all(ref[2][~keep] <= ov.TOL * 0.3)  # faces of at most 0.6 x 0.5 m
    id1, id2 = new[0], new[1]
    assert np.all(id1 < id2)
    assert np.all(np.diff(id1 * len(args[1]) + id2) > 0)  # lexicographic, no repeats
    assert np.all(args[9][id1] | args[9][id2])  # never two non-moving bodies
    six = ov.all_contacts(*args)
    assert all(np.array_equal(a, b) for a, b in zip(six, new[:6]))


def test_sweep_axis_follows_the_spread():
    """A tall column (spread along z), a long row (along x), a deep one (along y): the
    sweep's candidates clipped give the all-pairs contacts."""
    for shape in ((1, 2, 30), (30, 1, 2), (2, 30, 1)):
        args = packing(7, shape=shape)
        new = _candidates_clipped(args, False)
        ref = ov._contacts_all_pairs(*args)
        assert len(ref[0]) > 10
        assert all(np.array_equal(a, b) for a, b in zip(new, ref))


def test_apart_finds_separated_and_touching_boxes():
    """Unit cubes side by side along x: apart, touching, overlapping."""
    s = ov.Shapes([np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])] * 2)

    def apart(dx, tilt=0.0):
        p = np.array([[0.5, 0.5, 0.5], [1.5 + dx, 0.5, 0.5]])
        c, sn = np.cos(tilt), np.sin(tilt)
        r = np.stack([np.eye(3), np.array([[c, 0, sn], [0, 1, 0], [-sn, 0, c]])])
        GV, GN, GD, _, _ = ov._global_geometry(s.verts, s.nv, s.normals, s.offsets, s.nf, p, r)
        return ov._apart(GV[0], 8, GN[0], GD[0], 6, GV[1], 8, GN[1], GD[1], 6, ov.TOL)

    assert apart(1e-3) and apart(0.0) and apart(-0.5e-11)  # apart, touching, within TOL
    assert not apart(-1e-9) and not apart(-1e-3)  # overlapping by more than TOL
    assert not apart(0.0, tilt=1e-3)  # turned: an edge goes in by 0.5 mm


#: two stones of an irregular wall (irregular_wall seed 0, 20 courses of 25 stones of about
#: 0.6 x 0.3 x 0.6 m) at step 9 of a gravity run, touching on their sloping bed joint:
#: body-frame vertices (m), positions (m), rotation matrices
LOCAL_A = [[0.29999999999999993, 0.24169738320245296, 0.14685313449617468],
           [-0.3, 0.24169738320245296, 0.14685313449617474], [0.3, -0.2476720232413615, 0.14294926676661562],
           [-0.29999999999999993, -0.2476720232413615, 0.1429492667666157],
           [0.3, -0.22485914284291433, -0.15015399571379562],
           [-0.29999999999999993, -0.22485914284291433, -0.15015399571379556],
           [0.29999999999999993, 0.2309337844151754, -0.14659473797701533],
           [-0.3, 0.2309337844151754, -0.14659473797701528]]
LOCAL_B = [[-0.3348763981543035, -0.29999999999999993, -0.12911186321368862],
           [-0.33487639815430337, 0.2999999999999999, -0.12911186321368928],
           [0.29999106810899107, -0.3000000000000001, -0.1439328956934085],
           [0.2999910681089912, 0.2999999999999997, -0.14393289569340917],
           [0.3383177097425465, -0.2999999999999999, 0.12858432636346775],
           [0.3383177097425466, 0.29999999999999993, 0.1285843263634671],
           [-0.30365173450524213, -0.2999999999999997, 0.14345403530753612],
           [-0.303651734505242, 0.3000000000000001, 0.14345403530753545]]
POS = [[14.216663551802544, 4.232227847908088e-19, 3.173241278246855],
       [13.977167810765271, 7.093828852224249e-18, 3.458354230723913]]
ROT = [[[-2.220446049250313e-16, -0.9999748903484679, -0.007086513428335254],
        [-1.0000000000000002, -2.220446049250313e-16, 1.231653667943533e-16],
        [-1.231653667943533e-16, 0.007086513428335254, -0.999974890348468]],
       [[0.9997104988803974, -2.267920791568932e-16, -0.02406072376939017],
        [2.0506985761715758e-16, 1.0, -9.052757390790895e-16],
        [0.02406072376939017, 9.000795315415223e-16, 0.9997104988803974]]]


def test_touching_stones_are_no_contact():
    """The clip alone gives these touching stones a round-off 'overlap' (V ~ 1e-17 m^3,
    A_c ~ 1e-16 m^2, a 'depth' V/A_c of decimetres that stopped the run as tunnelling);
    the contact search gives no contact."""
    s = ov.Shapes([np.array(LOCAL_A), np.array(LOCAL_B)])
    args = (s.verts, s.nv, s.normals, s.offsets, s.nf, s.faces, s.fk, np.array(POS), np.array(ROT),
            np.array([True, True]), ov.TOL)
    ref = ov._contacts_all_pairs(*args)
    assert len(ref[0]) == 1 and ref[2][0] < tol.TOUCHING_VOLUME_M3 and ref[2][0] / ref[5][0] > 0.1
    assert len(ov.contacts_with_patches(*args)[0]) == 0


def test_blown_up_body_pairs_with_nothing():
    """A body with a non-finite position is no candidate; the all-pairs search finds no
    contact with it either."""
    args = list(packing(2))
    pos = args[7].copy()
    pos[5] = np.nan
    args[7] = pos
    lo, hi = _global(args)[3:]
    ia, ib = ov.sweep_pairs(lo, hi, args[9])
    assert 5 not in ia and 5 not in ib
    new = _candidates_clipped(args, False)
    ref = ov._contacts_all_pairs(*args)
    assert all(np.array_equal(a, b) for a, b in zip(new, ref))
    assert 5 not in ov.contacts_with_patches(*args)[0]


def test_no_moving_body_no_pair():
    args = list(packing(1))
    args[9] = np.zeros_like(args[9])
    assert len(ov.contacts_with_patches(*args)[0]) == 0
    assert len(ov.sweep_pairs(*_global(args)[3:], args[9])[0]) == 0
