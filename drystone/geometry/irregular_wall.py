"""Seeded generator of irregular dry-stone walls (convex polyhedral stones).

The wall face (x along the wall, z up) is cut into courses by bed joints that are
straight lines with a small random slope (the bottom one z = 0 and the top one z = H are
level); each course is cut into stones by straight head joints from bed joint to bed joint
that lean by a random amount, so that stones are convex quadrilaterals with non-vertical
joints. Neighbours share exact edge coordinates, so joints are exact (no gap, no overlap).
Head joints of consecutive courses are offset by at least ``stagger`` x the mean stone
length along their shared bed joint. Each stone is extruded through the thickness
(y from -T/2 to T/2; the wall tilts out of plane towards +y), or, with ``depth_spread`` > 0,
to a depth of its own: stones of varying depth, so that the wall's section is not constant
(the faces are ragged; ``flush`` keeps one face fair). The depths are drawn after the face
layout, so a seed gives the same face with or without them, and are scaled so that the
wall's volume (and weight) is that of the extruded wall. The first course is fixed to
the platform, a 0.05 m slab under the wall (top at z = 0) one stone length wider on each
side. Blocks are numbered course by course from the bottom, left to right, from 1; the
platform is block 0. Units: m, kg.
"""
from __future__ import annotations

import numpy as np

import drystone
from drystone.units import GRAVITY
from . import blockfile as bf
from . import params as pc

PLATFORM_THICKNESS = 0.05  # m


def thickness_for_weight(weight: float, density: float, length: float, height: float, g: float = GRAVITY) -> float:
    """Wall thickness (m) that gives ``weight`` (N) under gravity ``g`` (m/s^2): the stones tile
    the L x H face."""
    return weight / (density * g * length * height)


def _bed_joints(gen, rng, length, height, n_courses, slope_max, min_course, irregularity):
    """Bed joints as (z at x = 0, slope) per boundary, bottom and top level."""
    mean = height / n_courses
    for _ in range(1000):
        z0 = np.array([k * mean + (rng.uniform(-0.2, 0.2) * irregularity * mean if 0 < k < n_courses else 0.0)
                       for k in range(n_courses + 1)])
        slope = np.array([rng.uniform(-slope_max, slope_max) if 0 < k < n_courses else 0.0
                          for k in range(n_courses + 1)])
        lo = np.minimum(np.diff(z0), np.diff(z0) + np.diff(slope) * length)
        if lo.min() >= min_course:
            return list(zip(z0, slope))
    raise bf.GeometryError(f"geometry generator {gen!r}: could not place the bed joints: lower 'irregularity' "
                           f"({irregularity}) or the number of courses ({n_courses})")


def _head_joints(gen, rng, length, lmin, lmax, avoid, gap):
    """Joint positions along a bed joint: 0, ..., length, stones in [lmin, lmax] where
    possible, no joint within ``gap`` of any position in ``avoid``."""
    for _ in range(2000):
        xs = [0.0]
        ok = True
        while length - xs[-1] > lmax:
            for _try in range(50):
                x = xs[-1] + rng.uniform(lmin, lmax)
                if length - x >= lmin and all(abs(x - a) >= gap for a in avoid):
                    xs.append(x)
                    break
            else:
                ok = False
                break
        if ok:
            xs.append(length)
            return xs
    raise bf.GeometryError(f"geometry generator {gen!r}: could not stagger the head joints: widen 'stone_length' "
                           f"({lmin:g}-{lmax:g} m) or lower 'stagger'")


def _counted_joints(gen, rng, length, n, avoid, gap, min_fraction=0.5):
    """Joint positions for exactly n stones: random lengths (Dirichlet, concentration 4)
    of at least ``min_fraction`` x length / n, no joint within ``gap`` of ``avoid``."""
    lmin = min_fraction * length / n
    for _ in range(20000):
        w = rng.dirichlet(np.full(n, 4.0)) * length
        if w.min() < lmin:
            continue
        xs = np.concatenate([[0.0], np.cumsum(w)])
        xs[-1] = length
        if all(abs(x - a) >= gap for x in xs[1:-1] for a in avoid):
            return xs.tolist()
    raise bf.GeometryError(f"geometry generator {gen!r}: could not place {n} staggered stones in a course: "
                           "lower 'stagger' or the stone count ('stones_per_course')")


FLUSH = {None: 0.0, "+y": 1.0, "-y": -1.0}


def stone_depths(rng, areas, thickness, spread):
    """Depths (m) of stones of face areas ``areas`` (m^2): thickness x (1 + spread x u),
    u uniform in [-1, 1], then scaled so that sum(area x depth) = thickness x sum(area)
    (the volume of the extruded wall). ``spread`` = 0 gives the constant thickness."""
    areas = np.asarray(areas, float)
    if spread == 0:
        return np.full(len(areas), float(thickness))
    d = thickness * (1.0 + spread * rng.uniform(-1.0, 1.0, len(areas)))
    return d * (thickness * areas.sum() / (areas @ d))


def _area(quad):
    x, z = np.asarray(quad, float).T
    return 0.5 * abs(x @ np.roll(z, -1) - z @ np.roll(x, -1))


def make(length=1.5, height=0.375, thickness=0.108, courses=7, stone_length=(0.10, 0.20), irregularity=0.3,
         stagger=0.25, seed=0, density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8, first_course="fixed",
         name="irregular_wall", stones_per_course=None, depth_spread=0.0, flush=None, *,
         _generator="irregular_wall") -> dict:
    """An irregular wall as a block-file dict.

    ``stones_per_course``: optional list of stone counts per course (bottom first); it
    sets the number of courses and replaces ``stone_length``.
    ``irregularity`` in [0, 1): 0 gives level bed joints and vertical head joints (running
    bond); otherwise head joints lean by up to irregularity x 0.5 course height, bed joints
    rise by up to irregularity x 0.4 course height over the wall's length and their heights
    move by up to irregularity x 0.2 course height.
    ``depth_spread`` in [0, 1): 0 extrudes every stone through ``thickness``; otherwise each
    stone's depth is thickness x (1 +- depth_spread), rescaled to keep the wall's volume
    (``stone_depths``). ``flush``: None centres every stone on the wall's mid-plane (both
    faces ragged); "+y" or "-y" keeps that face fair.
    Other parameters: sizes > 0 m, ``courses`` an integer >= 1, ``stone_length`` [min, max]
    with 0 < min < max <= length (m), ``stagger`` in [0, 1), ``seed`` an integer >= 0,
    ``first_course`` "fixed" or "free". ``_generator``: the name errors give (for the
    generators built on this one). Bad values raise GeometryError.
    """
    g = _generator
    for k, v in (("length", length), ("height", height), ("thickness", thickness)):
        pc.positive(g, k, v, "m")
    pc.integer(g, "courses", courses, lo=1)
    pc.numbers(g, "stone_length", stone_length, 2, lo=0, lo_open=True, unit="m")
    lmin, lmax = stone_length
    if not lmin < lmax <= length:
        raise pc.fail(g, "stone_length", f"[min, max] with 0 < min < max <= length ({length} m)", stone_length)
    pc.number(g, "irregularity", irregularity, 0, 1, hi_open=True)
    pc.number(g, "stagger", stagger, 0, 1, hi_open=True)
    pc.integer(g, "seed", seed, lo=0)
    pc.material(g, density, kn, kt, damping, mu=mu)
    pc.choice(g, "first_course", first_course, ["fixed", "free"])
    if not isinstance(name, str) or not name:
        raise pc.fail(g, "name", "a non-empty string", name)
    if stones_per_course is not None and not (isinstance(stones_per_course, (list, tuple)) and stones_per_course
                                              and all(bf.is_int(n) and n >= 1 for n in stones_per_course)):
        raise pc.fail(g, "stones_per_course", "a non-empty list of integers >= 1 (bottom course first)",
                      stones_per_course)
    pc.number(g, "depth_spread", depth_spread, 0, 1, hi_open=True)
    pc.choice(g, "flush", flush, list(FLUSH))
    rng = np.random.default_rng(seed)
    if stones_per_course is not None:
        courses = len(stones_per_course)
    ch = height / courses
    beds = _bed_joints(g, rng, length, height, courses, 0.4 * irregularity * ch / length, 0.5 * ch, irregularity)
    lean_max = 0.5 * irregularity * ch
    gap = stagger * 0.5 * (lmin + lmax)

    def z_at(k, x):
        z0, s = beds[k]
        return z0 + s * x

    faces = []  # (course, quad) in block order
    previous_top: list[float] = []
    for k in range(courses):
        if stones_per_course is not None:
            gap = stagger * length / stones_per_course[k]
            xb = _counted_joints(g, rng, length, stones_per_course[k], previous_top[1:-1], gap)
        else:
            xb = _head_joints(g, rng, length, lmin, lmax, previous_top[1:-1], gap)
        lean = [0.0] + [rng.uniform(-lean_max, lean_max) for _ in xb[1:-1]] + [0.0]
        xt = [x + d for x, d in zip(xb, lean)]
        for j in range(len(xb) - 1):
            faces.append((k, [(xb[j], z_at(k, xb[j])), (xb[j + 1], z_at(k, xb[j + 1])),
                              (xt[j + 1], z_at(k + 1, xt[j + 1])), (xt[j], z_at(k + 1, xt[j]))]))
        previous_top = xt
    depths = stone_depths(rng, [_area(q) for _, q in faces], thickness, depth_spread)
    centres = FLUSH[flush] * (thickness - depths) / 2  # on the mid-plane, or flush with a face
    half = float(np.max(np.abs(centres) + depths / 2))
    blocks = [{"id": 0, "role": "platform", "material": "stone",
               "vertices": bf.box_vertices((length / 2, 0.0, -PLATFORM_THICKNESS / 2),
                                           (length + 2 * lmax, 2 * half + 2 * lmax, PLATFORM_THICKNESS))}]
    for bid, ((k, quad), d, yc) in enumerate(zip(faces, depths, centres), start=1):
        verts = [[x, y, z] for x, z in quad for y in (yc - d / 2, yc + d / 2)]
        problem = bf.not_convex(verts)
        if problem:
            raise bf.GeometryError(f"geometry generator {g!r}: stone {bid} came out wrong ({problem}); "
                                   "lower 'irregularity'")
        blocks.append({"id": bid, "role": first_course if k == 0 else "free", "material": "stone",
                       "vertices": verts, "label": f"course {k + 1}"})
    params = dict(length=length, height=height, thickness=thickness, courses=courses,
                  stone_length=list(stone_length), irregularity=irregularity, stagger=stagger, seed=seed,
                  density=density, kn=kn, kt=kt, mu=mu, damping=damping, first_course=first_course,
                  stones_per_course=stones_per_course, depth_spread=depth_spread, flush=flush)
    return {"format": bf.FORMAT, "version": bf.VERSION, "name": name,
            "description": f"irregular dry-stone wall, seed {seed} (drystone/geometry/irregular_wall.py)",
            "units": {"length": "m", "mass": "kg"},
            "materials": {"stone": {"density": density, "kn": kn, "kt": kt, "mu": mu, "damping": damping}},
            "blocks": blocks,
            "generator": dict(params, name="irregular_wall", drystone_version=drystone.__version__)}


SANTA_CRUZ_DEPTH_SPREAD = 1 / 3  # = the stone lengths' spread, 0.10-0.20 m around 0.15 m


#: parameters of ``make`` that ``tilt_wall`` passes on
TILT_OVER = ("irregularity", "stagger", "first_course", "stones_per_course", "flush")


def tilt_wall(seed=0, weight=1371.0, density=2300.0, kn=2e8, kt=1e8, mu=0.4, damping=0.8,
              depth_spread=SANTA_CRUZ_DEPTH_SPREAD, **over) -> dict:
    """The Santa-Cruz et al. tilt-table wall of the Sacsayhuaman paper §3.2: 1500 mm long,
    375 mm high, stones about 150 mm long (x) and 50 mm high (7 courses of 53.6 mm), about
    100 mm deep; the mean thickness is chosen so the wall weighs ``weight`` = 1371 N at
    ``density`` = 2300 kg/m^3: 0.1080 m. The tested walls had no constant cross-section
    (§3.2), so by default every stone has a depth of its own, 0.108 m x (1 +- 1/3) (the
    relative spread of the stone lengths: stones irregular alike in all three dimensions),
    centred on the mid-plane; ``depth_spread = 0`` gives stones extruded through 0.108 m.
    Contact properties: Table 1, FEM column. ``over``: any of TILT_OVER, passed to ``make``."""
    g = "tilt_wall"
    unknown = sorted(set(over) - set(TILT_OVER))
    if unknown:
        allowed = ["seed", "weight", *bf.MATERIAL_PROPERTIES, "depth_spread", *TILT_OVER]
        raise bf.GeometryError(f"geometry generator {g!r}: unknown parameter(s) {unknown}; allowed: {allowed}")
    pc.positive(g, "weight", weight, "N")
    pc.material(g, density, kn, kt, damping, mu=mu)
    length, height = 1.5, 0.375
    t = thickness_for_weight(weight, density, length, height)
    d = make(length=length, height=height, thickness=t, courses=7, stone_length=(0.10, 0.20), seed=seed,
             density=density, kn=kn, kt=kt, mu=mu, damping=damping, name="tilt_wall",
             depth_spread=depth_spread, _generator=g, **over)
    g = d["generator"]
    assumed = [f"tilt wall generated (seed {seed}), not the tested walls' stones: the real outlines are not available "
               "(ASSUMED)",
               f"{g['courses']} courses of {1e3 * height / g['courses']:.1f} mm (ASSUMED from the stones' ~50 mm height "
               "and the wall's 375 mm)",
               f"stone lengths {g['stone_length'][0]:.2f}-{g['stone_length'][1]:.2f} m with leaning head joints "
               "(ASSUMED from the stones' ~150 mm)"]
    if g["depth_spread"]:
        assumed.append(f"stone depths {t:.4f} m x (1 ± {g['depth_spread']:.3g}) (ASSUMED: the relative spread of "
                       "the stone lengths; the paper says only that the walls had no constant section)")
    else:
        assumed.append(f"constant section: every stone extruded through {t:.4f} m (as the paper's model)")
    g["assumed"] = assumed
    return d
