"""Issue 23, item 5: vertices per block. A block of 10 000 distinct vertices took 16-30 s
and 6.3 GB before it was accepted (and YADE then failed: the contact kernel cannot take
it). A block with more than ``MAX_VERTICES_PER_BLOCK`` vertices is now refused, naming the
file, the block and the limit, before its hull or any check over pairs of vertices; the
limit is the most vertices any convex block can have and still fit the contact kernel;
the convexity check of a block no longer builds n x n matrices and decides as before."""
import itertools
import json
import math
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import tolerances as tol
from conftest import refused_run
from drystone.mechanics import overlap as ov
from drystone.geometry import blockfile as bf
from drystone.geometry import polyhedron as ph

ROOT = Path(__file__).resolve().parents[1]
LIMIT = bf.MAX_VERTICES_PER_BLOCK


def sphere(n, r=0.2, centre=(0.0, 0.0, 0.25)):
    """n distinct points on a sphere (Fibonacci lattice), each a corner of their hull (m)."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5 ** 0.5) * k
    s = np.sqrt(1 - z * z)
    return (np.c_[s * np.cos(phi), s * np.sin(phi), z] * r + centre).tolist()


def truncated_icosahedron(edge_scale=0.04):
    """The 60 corners of a truncated icosahedron (12 pentagons, 20 hexagons; m): the cyclic
    permutations of (0, +-1, +-3 phi), (+-1, +-(2 + phi), +-2 phi), (+-phi, +-2, +-(2 phi + 1))."""
    f = (1 + 5 ** 0.5) / 2
    pts = set()
    for base in ((0, 1, 3 * f), (1, 2 + f, 2 * f), (f, 2, 2 * f + 1)):
        for signs in itertools.product((1, -1), repeat=3):
            p = [x * s for x, s in zip(base, signs)]
            pts.update(tuple(float(p[(i + r) % 3]) for i in range(3)) for r in range(3))
    return (np.array(sorted(pts)) * edge_scale + (0.0, 0.0, 0.25)).tolist()


def blocks_file(vertices):
    """The block of ``vertices`` (id 1, listed first) on a platform (id 0)."""
    return {"format": bf.FORMAT, "version": 1, "name": "t",
            "materials": {"stone": {"density": 2300, "kn": 2e8, "kt": 1e8, "mu": 0.4, "damping": 0.8}},
            "blocks": [{"id": 1, "role": "free", "material": "stone", "vertices": vertices},
                       {"id": 0, "role": "platform", "material": "stone",
                        "vertices": bf.box_vertices((0, 0, -0.05), (1, 1, 0.1))}]}


# --- the limit --------------------------------------------------------------------------

def test_limit_is_the_most_vertices_the_contact_kernel_can_take():
    """overlap.Shapes refuses blocks whose faces F plus the corners k of their largest face
    exceed MAXV // 2. A convex block of V corners has F >= V/2 + 2 (every corner on >= 3
    edges, Euler) and F >= (2V - 4)/(k - 2) (every face has <= k corners): the largest V
    for which some k gives F + k <= MAXV // 2 is the limit (80 for MAXV = 96)."""
    room = ov.MAXV // 2

    def could_fit(v):
        return any(max(math.ceil(v / 2 + 2), math.ceil((2 * v - 4) / (k - 2))) + k <= room for k in range(3, room))

    assert max(v for v in range(4, 10 * ov.MAXV) if could_fit(v)) == LIMIT
    # the kernel agrees on blocks at hand: a 60-corner truncated icosahedron (F = 32,
    # k = 6) fits, so does a 24-point sphere (triangles: F = 2V - 4 = 44, k = 3), a
    # 25-point one does not, nor does a block just above the limit
    for v in (truncated_icosahedron(), sphere(24)):
        ov.Shapes([np.array(v)])
        bf.parse(blocks_file(v))
    for n in (25, LIMIT + 1):
        with pytest.raises(ValueError, match="exceed the overlap kernel's polygon buffer"):
            ov.Shapes([np.array(sphere(n))])


@pytest.mark.parametrize("n", [LIMIT + 1, 10_000])
def test_block_above_the_limit_is_refused_before_its_hull(tmp_path, monkeypatch, n):
    """Named file, block and limit, one line; no hull, convexity or pair check runs (the
    10 000-vertex block used 6.3 GB in them)."""
    def must_not_run(*args, **kwargs):
        raise AssertionError("the vertex count must be refused before the hull and the convexity check")

    monkeypatch.setattr(ph, "hull", must_not_run)
    monkeypatch.setattr(ph, "corner_gaps", must_not_run)
    monkeypatch.setattr(bf, "not_convex", must_not_run)
    p = tmp_path / "scan.json"
    p.write_text(json.dumps(blocks_file(sphere(n))))
    with pytest.raises(bf.GeometryError) as err:
        bf.load(p)
    msg = str(err.value)
    assert msg.startswith(f"{p}: block 1: {n} vertices, more than {LIMIT} vertices"), msg
    assert "MAX_VERTICES_PER_BLOCK" in msg and "\n" not in msg


def test_block_at_the_limit_is_accepted_as_given(tmp_path):
    v = sphere(LIMIT)
    p = bf.write(blocks_file(v), tmp_path / "at_limit.json")
    b = bf.load(p).block(1)
    assert len(b.vertices) == LIMIT and np.array_equal(b.vertices, v)


def test_cli_refuses_with_one_line(tmp_path):
    """``drystone run`` exits 2 with one line, before YADE (which failed on this block after
    37 s and 6.4 GB); ``drystone.geometry validate`` exits 1."""
    (tmp_path / "big.json").write_text(json.dumps(blocks_file(sphere(10_000))))
    case = tmp_path / "big.toml"
    case.write_text('[case]\nname = "big_block"\ngeometry = "big.json"\n\n'
                    '[[stages]]\ntype = "gravity"\nduration = 0.1\n')
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "drystone", "run", str(case), "--out", str(out)],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 2, r.stderr
    assert r.stderr.splitlines() == [f"error: {tmp_path / 'big.json'}: block 1: 10000 vertices, more than {LIMIT} "
                                     f"vertices (drystone.geometry.blockfile.MAX_VERTICES_PER_BLOCK: no convex block "
                                     "with more corners fits the contact kernel); give the stone's hull fewer corners"]
    assert not out.exists()
    r = subprocess.run([sys.executable, "-m", "drystone.geometry", "validate", str(tmp_path / "big.json")],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 1 and len(r.stderr.splitlines()) == 1 and "more than" in r.stderr


# --- the convexity check: linear memory, the same decisions ----------------------------

def _old_gaps(v, h):
    """The former polyhedron.corner_gaps (an n x n matrix of products)."""
    nsum = np.zeros_like(v)
    np.add.at(nsum, h.simplices, h.equations[:, None, :3])
    norm = np.linalg.norm(nsum, axis=1)
    p = (nsum / np.where(norm > 0, norm, 1.0)[:, None]) @ v.T
    others = p.copy()
    np.fill_diagonal(others, -np.inf)
    gaps = np.full(len(v), -np.inf)
    gaps[h.vertices] = (np.diag(p) - others.max(axis=1))[h.vertices]
    return gaps


def _old_decision(v):
    """The former blockfile.not_convex's decision: ("coincide", i, j) from an n x n x 3
    distance array, ("corners", bad indices) or None."""
    h = ph.hull(v)
    t = bf.CORNER_REL_TOL * float(np.linalg.norm(np.ptp(v, axis=0)))
    dist = np.linalg.norm(v[:, None, :] - v[None, :, :], axis=2)
    i, j = np.nonzero(np.triu(dist <= t, k=1))
    if len(i):
        return ("coincide", i[0], j[0])
    bad = np.flatnonzero(~(_old_gaps(v, h) > t))
    return ("corners", bad) if len(bad) else None


def _vertex_sets(rng, count):
    """Boxes, spheres and random hulls, turned, with repeated, nearly repeated, inner, face
    and edge points inserted at random places."""
    for _ in range(count):
        kind = rng.integers(3)
        if kind == 0:
            v = np.array(bf.box_vertices((0, 0, 0), rng.uniform(0.1, 2, 3)))
        elif kind == 1:
            v = np.array(sphere(int(rng.integers(6, LIMIT + 1)), r=float(rng.uniform(0.05, 1))))
        else:
            u = rng.normal(size=(int(rng.integers(5, 40)), 3))
            v = u / np.linalg.norm(u, axis=1)[:, None] * rng.uniform(0.1, 1, 3)
        v = v @ np.linalg.qr(rng.normal(size=(3, 3)))[0] + rng.uniform(-5, 5, 3)
        t = bf.CORNER_REL_TOL * float(np.linalg.norm(np.ptp(v, axis=0)))
        h = ph.hull(v)
        a, b = h.simplices[0][:2]
        extras = {"repeat": lambda: v[rng.integers(len(v))],
                  "near": lambda: v[rng.integers(len(v))] + rng.normal(size=3) * 0.2 * t,
                  "apart": lambda: v[rng.integers(len(v))] + rng.normal(size=3) * 20 * t,
                  "inner": lambda: v.mean(axis=0),
                  "face": lambda: v[h.simplices[0]].mean(axis=0),
                  "edge": lambda: (v[a] + v[b]) / 2}
        for name in rng.choice(list(extras), size=int(rng.integers(0, 3))):
            v = np.insert(v, int(rng.integers(len(v) + 1)), extras[name](), axis=0)
        yield v


def test_convexity_decisions_are_those_of_the_n_squared_check():
    """Same pair named for repeated vertices (the first in file order), same vertices named
    as not corners, same acceptance; the gaps themselves agree to round-off."""
    outcomes = {"accepted": 0, "coincide": 0, "corners": 0}
    for v in _vertex_sets(np.random.default_rng(23), 300):
        old, new = _old_decision(v), bf.not_convex(v)
        gaps_old, gaps_new = _old_gaps(v, ph.hull(v)), ph.corner_gaps(v, rows=7)  # several row blocks
        assert np.array_equal(np.isinf(gaps_old), np.isinf(gaps_new))
        finite = np.isfinite(gaps_old)
        assert np.allclose(gaps_new[finite], gaps_old[finite], rtol=0, atol=tol.EXACT_ABS)
        if old is None:
            assert new is None
            outcomes["accepted"] += 1
        elif old[0] == "coincide":
            assert new.startswith(f"vertices {old[1]} and {old[2]} coincide at ({bf._xyz(v[old[1]])}) m"), new
            outcomes["coincide"] += 1
        else:
            named = ", ".join(f"vertex {k} at ({bf._xyz(v[k])}) m" for k in old[1][:4])
            assert new.startswith(f"not convex: {named} "), new
            outcomes["corners"] += 1
    assert min(outcomes.values()) >= 30, outcomes  # every outcome tried


def test_two_repeated_vertices_name_the_first_pair_in_file_order():
    """Vertex 3 is repeated at 8 and vertex 1 at 9: the pair (1, 9) is named (the smallest
    first index, then second), as before."""
    v = bf.box_vertices((0, 0, 0.5), (1, 1, 1))
    v = v + [v[3], v[1]]
    assert bf.not_convex(v).startswith("vertices 1 and 9 coincide at (-0.5, -0.5, 1) m")
    assert _old_decision(np.array(v))[1:] == (1, 9)


def test_convexity_check_memory_is_below_one_n_by_n_matrix():
    """3000 points (above the limit: not_convex is also called on generated stones): the
    former check held n x n x 3 distances (216 MB); now rows of 256 x n products."""
    n = 3000
    v = np.array(sphere(n))
    tracemalloc.start()
    try:
        assert bf.not_convex(v) is None
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < n * n * 8, f"peak {peak / 1e6:.0f} MB"


# --- blocks within the limit that the kernel still cannot take --------------------------

def test_too_large_agrees_with_the_kernel():
    """overlap.too_large is the kernel's own rule (Shapes), skipping only blocks that Euler's
    formula proves fit (2V - 1 <= MAXV // 2)."""
    for v in (truncated_icosahedron(), sphere(24), sphere(25), sphere(40), sphere(LIMIT),
              bf.box_vertices((0, 0, 0), (1, 2, 3))):
        try:
            ov.Shapes([np.array(v)])
            fits = True
        except ValueError:
            fits = False
        assert (ov.too_large(v) is None) == fits, len(v)


def test_a_block_the_kernel_cannot_take_is_refused_before_yade(tmp_path):
    """A 30-point sphere passes the block file's checks (<= 80 vertices) but has 56 faces:
    YADE failed on it with a 44-line traceback. Now one line, exit 2, naming file and block."""
    err = refused_run(tmp_path, blocks_file(sphere(30)))
    assert f"{tmp_path / 'blocks.json'}: block 1: 56 faces" in err and "polygon buffer" in err
