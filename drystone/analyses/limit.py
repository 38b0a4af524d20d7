"""Limit analysis of any case's wall: the collapse multiplier and mechanism of a horizontal
body force lambda x (self-weight), both frictions, in seconds (no YADE, no run).

``python -m drystone limit CASE [--towards +y -y +x -x | all] [--friction associative coulomb]``
writes results/<case>/limit/: limit.json, mechanism_<dir>_<friction>.png (stones coloured by
their virtual speed on the wall's elevation and in 3D) and report.html.

The wall is the case's geometry as built, or with ``--settled`` after the case's settling
run (``settled_wall``: YADE, the modal analysis's settling stages) (any input path: block file, generators,
outlines, DXF, meshes; a stone of several convex parts is one body), its stones' masses
from the case's materials, friction per pair as the runs take it
(``drystone.mechanics.contact.pair_properties``: the smaller mu, a joint's own mu where the
geometry gives one), gravity the case's [physics] gravity. The interfaces are the faces the
stones share (``drystone.mechanics.interfaces``); the LP and the non-associative iteration
are ``drystone.mechanics.limit_analysis``; the formulation and its limits: docs/limit-analysis.md.

A tilt of the platform by theta is, for rigid blocks, a body force of horizontal/vertical
ratio tan(theta): the tilt angle at collapse is atan(lambda) (``angle_deg``). The case's
stages, [[forces]] and [[loads]] are not part of this analysis (listed as ``ignored``).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drystone.geometry import blockfile as bf
from drystone.kept import Kept
from drystone.mechanics import interfaces as itf
from drystone.mechanics import limit_analysis as la
from drystone.mechanics.contact import pair_properties
from drystone.model.keys import CaseError
from drystone.model.stages import TOWARDS

HELP = "rigid-block limit analysis: collapse multiplier (tilt angle) and mechanism by linear programming"
FRICTIONS = ("associative", "coulomb")
NAME = "limit"


@dataclass
class Wall:
    """A case's wall for the analysis: ``bodies`` and ``ifaces`` (``limit_analysis``), ``mu``
    per interface, ``gravity`` m/s^2 (magnitude), ``parts`` per body (convex parts, m),
    ``roles`` per body, ``name`` and ``ignored`` (the case's loads this analysis leaves out);
    ``settlement_m``: the largest vertex displacement of a settled wall from as built (None
    as built)."""
    name: str
    bodies: la.Bodies
    ifaces: list
    mu: np.ndarray
    gravity: float
    parts: list
    roles: list
    ignored: list
    settlement_m: float | None = None


def wall_of(bs: bf.BlockSet, mats: dict, gravity: float, name: str = "", ignored=()) -> Wall:
    """The analysis' wall of a block set; ``mats``: material name -> properties (density,
    mu, ...), as the runs resolve them."""
    ids, mass, cen, fixed, blocked, size, parts, roles = [], [], [], [], [], [], [], []
    for b in bs.blocks:
        m = b.mass_properties(mats[b.material]["density"])
        ids.append(b.id)
        mass.append(m.mass)
        cen.append(m.centroid)
        fixed.append(b.role != "free")
        blocked.append(b.blocked_dofs)
        size.append(float(np.ptp(b.points, axis=0).max()))
        parts.append(list(b.parts))
        roles.append(b.role)
    bodies = la.Bodies(ids, np.array(mass), np.array(cen), np.array(fixed), blocked, np.array(size))
    ifaces = itf.find(parts, bodies.fixed)
    joints = {tuple(sorted(j["blocks"])): j for j in bs.joints}
    mu = np.array([pair_properties(mats[bs.blocks[f.a].material], mats[bs.blocks[f.b].material],
                                   joints.get(tuple(sorted((ids[f.a], ids[f.b])))))["mu"] for f in ifaces])
    return Wall(name, bodies, ifaces, mu, float(gravity), parts, roles, list(ignored))


def load_wall(case_path, overrides=()) -> Wall:
    """The wall of a case file (geometry as built; CaseError / GeometryError name the file)."""
    import tempfile

    from drystone.model import case as casemod
    from drystone.model import resolve

    case = casemod.load(case_path, list(overrides))
    with tempfile.TemporaryDirectory() as tmp:  # the resolver writes the geometry it read there
        bs, _ = resolve._geometry(case, str(case_path), Path(tmp))
    mats = resolve._materials(case, bs, str(case_path))
    ignored = (["[[forces]]"] if case["forces"] else []) + (["[[loads]]"] if case["loads"] else [])
    return wall_of(bs, mats, case["physics"]["gravity"], case["case"]["name"], ignored)


def settled_wall(case_path, overrides=(), root=None, log=print) -> Wall:
    """The wall of a case after the modal analysis's settling run (its gravity stages, YADE;
    the run in ``root``/runs/settle, ``root`` default the analysis folder, reused when its
    inputs are unchanged): the stones at
    their settled positions (platform frame), masses and centroids of the moved stones,
    friction as built, and the interfaces by the face test on the settled stones with the
    tolerance of the largest settlement (a vertex's displacement from as built), at least
    ``interfaces.TOL``: faces that settling tilted or pressed into each other by up to that
    much still count as touching, their common polygon (on the first stone's face) the
    interface."""
    from drystone.analyses import common
    from drystone.analyses import modal as modal_analysis
    from drystone.mechanics import modal as modal_mech
    from drystone.postprocess import identification as idf
    from drystone.postprocess import summary as summ
    from drystone.simulate import RunError

    case_path = Path(case_path).expanduser().resolve()
    built = load_wall(case_path, overrides)
    stages, _ = modal_analysis.settle_stages(case_path, overrides)
    root = common.output_dir(case_path, NAME, root)
    done = common.run_jobs(case_path, [("settle", [modal_analysis.stages_override(stages)])], root, "limit_settle",
                           list(overrides), log=log)
    st = done["settle"]
    if st["status"] != "done" or st.get("collapsed"):
        raise RunError(f"{case_path}: the settling run " + ("failed: " + str(st.get("error")) if st["status"] != "done"
                                                              else f"collapsed (stones {st.get('collapsed_stones')})"))
    run_dir = Path(st["run_dir"])
    asm = idf.wall_assembly(run_dir, time_s=float(np.asarray(summ.load_histories(run_dir)["t"])[-1]))
    by_id = {bid: k for k, bid in enumerate(asm.ids)}
    parts, cen = [], []
    moved = 0.0
    for b, bid in enumerate(built.bodies.ids):
        k = by_id[bid]
        v = asm.vertices[k]
        ps = [np.asarray(p, float) for p in (v if isinstance(v, list) else [v])]
        parts.append(ps)
        moved = max(moved, max(float(np.abs(p - q).max()) for p, q in zip(ps, built.parts[b])))
        cen.append(modal_mech.mass_properties(ps, float(asm.density[k]))[1])
    tol = max(itf.TOL, moved)
    bodies = la.Bodies(built.bodies.ids, built.bodies.mass, np.array(cen), built.bodies.fixed, built.bodies.blocked,
                       built.bodies.size)
    ifaces = itf.find(parts, bodies.fixed, tol)
    mu_of = {tuple(sorted((f.a, f.b))): m for f, m in zip(built.ifaces, built.mu)}
    mu_default = float(built.mu.min()) if len(built.mu) else 0.0
    mu = np.array([mu_of.get(tuple(sorted((f.a, f.b))), mu_default) for f in ifaces])
    return Wall(built.name, bodies, ifaces, mu, built.gravity, parts, built.roles, built.ignored, moved)


def directions(towards) -> list[str]:
    """The load directions asked for: names of TOWARDS, or "all"."""
    out = []
    for t in towards:
        for k in (TOWARDS if t == "all" else [t]):
            if k not in TOWARDS:
                raise CaseError(f"--towards {k!r}: one of {sorted(TOWARDS)} or all")
            if k not in out:
                out.append(k)
    return out


def one(wall: Wall, towards: str, friction: str, facets: int = la.FACETS) -> tuple[dict, la.Result]:
    """One direction and friction: the JSON entry and the solver's result."""
    g = (0.0, 0.0, -wall.gravity)
    fn = la.solve if friction == "associative" else la.solve_coulomb
    r = fn(wall.bodies, wall.ifaces, wall.mu, TOWARDS[towards], g, facets)
    ok = r.status in ("collapse", "not_converged")
    entry = {"status": r.status, "friction": friction,
             "multiplier": r.multiplier if ok else None,
             "angle_deg": math.degrees(math.atan(r.multiplier)) if ok else None,
             "solve_s": r.solve_s}
    if r.status == "cannot_stand":
        entry["message"] = (f"the wall cannot carry its own weight: the largest multiplier is {r.multiplier:.4g} < 0 "
                            "(it needs a push against the load direction to stand)")
    elif r.status in ("infeasible", "unbounded", "failed"):
        entry["message"] = {"infeasible": "no statically admissible interface forces at any multiplier: the wall "
                            "cannot carry its own weight (a stone resting on nothing, an overhang)",
                            "unbounded": "no multiplier makes the wall collapse: no stone can move",
                            }.get(r.status, f"the LP solver failed: {r.message}")
    elif r.status == "not_converged":
        entry["message"] = r.message
    if friction == "associative" and r.status == "collapse":
        entry["cone_bracket"] = cone_bracket(wall, towards, facets, r.multiplier)
    if friction == "coulomb":
        entry["converged"] = r.converged
        entry["coulomb_residual"] = r.coulomb_residual
        entry["iterations"] = r.iterations
        entry["history"] = [float(x) for x in r.history]
    if ok and r.velocity is not None:
        entry["mechanism"] = la.mechanism(wall.bodies, wall.ifaces, r.velocity)
    else:
        entry["mechanism"] = None
    return entry, r


def cone_bracket(wall: Wall, towards: str, facets: int, inscribed: float) -> dict:
    """Where the exact Coulomb cone's associative multiplier lies: between the inscribed
    pyramid's (``inscribed``, the analysis's own: every force it admits is inside the cone)
    and the circumscribed pyramid's (``la.assemble``'s ``outer``: it admits every force of the
    cone; a face touches the cone along the load). Maximising lambda over a larger admissible
    set never gives less, so the cone's lambda is in [inscribed, circumscribed]; one more LP."""
    g = (0.0, 0.0, -wall.gravity)
    r = la.solve(wall.bodies, wall.ifaces, wall.mu, TOWARDS[towards], g, facets, outer=True)
    hi = r.multiplier if r.status == "collapse" else None
    return {"multiplier": [inscribed, hi],
            "angle_deg": [math.degrees(math.atan(inscribed)), None if hi is None else math.degrees(math.atan(hi))],
            "circumscribed_status": r.status,
            "note": (f"the exact Coulomb cone's associative multiplier lies between the inscribed {facets}-facet "
                     "pyramid's (the analysis's) and the circumscribed one's; a wide bracket: the stones slip "
                     "off the load direction, refine with --facets 16 or 32")}


def analyse(wall: Wall, towards=("+y",), frictions=FRICTIONS, facets: int = la.FACETS) -> tuple[dict, dict]:
    """{"directions": {dir: entry}} and the solver results by (dir, friction). An entry is the
    last friction's (coulomb when both are asked: the physical one) with ``by_friction``
    holding every friction's entry."""
    out, results = {}, {}
    for t in directions(towards):
        by = {}
        for fr in frictions:
            by[fr], results[(t, fr)] = one(wall, t, fr, facets)
        out[t] = dict(by[frictions[-1]], by_friction=by)
    return {"directions": out}, results


def _wall_key(wall: Wall, dirs: list[str]) -> str:
    """A digest of everything the limit angles depend on: the wall's bodies, interfaces and
    friction, the directions, the pyramid and this analysis's code."""
    import hashlib

    h = hashlib.sha256()
    b = wall.bodies
    for a in (b.mass, b.centroid, b.fixed, b.size, np.asarray(wall.mu, float)):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr(b.blocked).encode())
    for f in wall.ifaces:
        h.update(np.ascontiguousarray(f.polygon).tobytes() + np.ascontiguousarray(f.normal).tobytes())
        h.update(f"{f.a},{f.b};".encode())
    h.update(f"{dirs}|{la.FACETS}|{wall.gravity!r}".encode())
    for src in (Path(la.__file__), Path(__file__)):
        h.update(src.read_bytes())
    return h.hexdigest()


#: this process's angles by ``_wall_key`` (``beside_dem``): analyses of one wall (a study's walls
#: with and without their loads, which this analysis leaves out) solve it once
_KEPT = Kept(32)


def beside_dem(case_path, towards, overrides=(), cache_dir=None) -> dict:
    """The rigid limit angles of a case's wall as built, per direction, to set beside a DEM
    tilt angle: {dir: {"associative_deg", "coulomb_deg", "associative_status",
    "coulomb_status", "associative_cone_deg" (the exact cone's bracket, ``cone_bracket``), "note"}}
    (an angle None where the status is not a collapse, or
    not_converged: the note says why). A wall this analysis cannot read gives
    {"error": one line} instead (the DEM analysis goes on). ``cache_dir``: the angles are
    kept in its ``limit_beside_dem.json`` and reused while the wall, the directions and this
    code are unchanged (a digest of them: ``_wall_key``), as they are in this process (``_KEPT``)."""
    from drystone.geometry.blockfile import GeometryError

    try:
        wall = load_wall(case_path, overrides)
    except (CaseError, GeometryError, ValueError) as e:
        return {"error": f"the limit analysis could not read the wall: {str(e).splitlines()[0]}"}
    dirs = directions(towards)
    cache = Path(cache_dir) / "limit_beside_dem.json" if cache_dir is not None else None
    key = _wall_key(wall, dirs)
    if cache is not None and cache.is_file():
        try:
            kept = json.loads(cache.read_text())
            if kept.get("key") == key:
                return kept["limits"]
        except (OSError, ValueError, KeyError, AttributeError):
            pass  # unreadable: computed again and rewritten
    if key in _KEPT:
        out = _KEPT.get(key)
        if cache is not None:
            _keep(cache, key, case_path, overrides, out)
        return out
    out = {}
    for t in dirs:
        e = {}
        for fr in FRICTIONS:
            entry, _ = one(wall, t, fr)
            collapse = entry["status"] == "collapse"
            e[f"{fr}_deg"] = entry["angle_deg"] if collapse else None
            e[f"{fr}_status"] = entry["status"]
            if entry.get("cone_bracket"):
                e["associative_cone_deg"] = entry["cone_bracket"]["angle_deg"]
            if not collapse:
                e.setdefault("note", entry.get("message", entry["status"]))
        e["note"] = e.get("note", "rigid stones, the geometry as built (docs/limit-analysis.md)")
        out[t] = e
    _KEPT.put(key, out)
    if cache is not None:
        _keep(cache, key, case_path, overrides, out)
    return out


def _keep(cache: Path, key: str, case_path, overrides, out: dict) -> None:
    """``beside_dem``'s angles into its cache file."""
    from drystone.analyses import common

    cache.parent.mkdir(parents=True, exist_ok=True)
    common.write_json(cache, {"key": key, "case": str(case_path), "overrides": list(overrides), "limits": out},
                      overrides=overrides)


def _speeds(wall: Wall, v) -> np.ndarray:
    b = wall.bodies
    sp = np.zeros(len(b.ids))
    if v is None:
        return sp
    for k, ps in enumerate(wall.parts):
        if b.fixed[k]:
            continue
        pts = np.vstack(ps)
        sp[k] = float(np.linalg.norm(v[k, :3] + np.cross(v[k, 3:], pts - b.centroid[k]), axis=1).max())
    return sp


def figure(wall: Wall, v, title: str, path: Path) -> Path:
    """The mechanism: stones coloured by their largest virtual speed (normalised), on the
    elevation (x-z, with the centroids' in-plane velocity as arrows) and in 3D."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    from scipy.spatial import ConvexHull

    from drystone.geometry import polyhedron as ph

    sp = _speeds(wall, v)
    top = sp.max() if sp.max() > 0 else 1.0
    cmap = plt.get_cmap("viridis")
    fig = plt.figure(figsize=(13, 5.2))
    ax = fig.add_subplot(1, 2, 1)
    polys, cols = [], []
    ax3 = fig.add_subplot(1, 2, 2, projection="3d")
    faces3, cols3 = [], []
    for k, ps in enumerate(wall.parts):
        c = "0.6" if wall.bodies.fixed[k] else cmap(sp[k] / top)
        for p in ps:
            xz = p[:, [0, 2]]
            try:
                h = ConvexHull(xz)
                polys.append(xz[h.vertices])
            except Exception:  # a part flat in elevation: no outline
                pass
            cols.append(c)
            f = ph.faces(p)
            for poly in f.polygons:
                faces3.append(p[poly])
                cols3.append(c)
    cols = cols[:len(polys)] if len(cols) != len(polys) else cols
    ax.add_collection(PolyCollection(polys, facecolors=cols, edgecolors="k", linewidths=0.4))
    if v is not None:
        moving = (sp > la.MOVING * top) & ~wall.bodies.fixed
        c = wall.bodies.centroid[moving]
        ax.quiver(c[:, 0], c[:, 2], v[moving, 0], v[moving, 2], color="r", angles="xy", width=0.003)
    ax.autoscale_view()
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_title("elevation: stones coloured by virtual speed (grey: fixed); arrows: in-plane velocity", fontsize=8)
    ax3.add_collection3d(Poly3DCollection(faces3, facecolors=cols3, edgecolors="k", linewidths=0.15))
    pts = np.vstack([p for ps in wall.parts for p in ps])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    mid, half = (lo + hi) / 2, (hi - lo).max() / 2
    ax3.set_xlim(mid[0] - half, mid[0] + half)
    ax3.set_ylim(mid[1] - half, mid[1] + half)
    ax3.set_zlim(mid[2] - half, mid[2] + half)
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z (m)")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, 1))
    fig.colorbar(sm, ax=[ax, ax3], shrink=0.7, label="virtual speed / largest (-)")
    fig.suptitle(title, fontsize=10)
    tmp = Path(path).with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=100)
    plt.close(fig)
    tmp.replace(path)
    return Path(path)


def _fmt(x, nd=3):
    return "—" if x is None else f"{x:.{nd}f}"


def markdown(wall: Wall, data: dict, figures: list[str]) -> str:
    """The report's text."""
    lines = [f"# Limit analysis: {wall.name}", "",
             f"{sum(~wall.bodies.fixed)} free stones, {int(wall.bodies.fixed.sum())} fixed bodies, "
             f"{len(wall.ifaces)} interfaces, {data['corners']} force points; geometry as built; friction mu "
             f"{data['mu_range'][0]:g}–{data['mu_range'][1]:g}; friction pyramid of {data['facets']} facets. "
             "A horizontal body force lambda x (self-weight) along the direction; a tilt of the platform by "
             "atan(lambda) is the same load on rigid blocks. Formulation and limits: docs/limit-analysis.md.", ""]
    if wall.ignored:
        lines += [f"The case's {', '.join(wall.ignored)} are not part of this analysis.", ""]
    lines += ["| direction | friction | status | lambda | tilt angle (deg) | exact cone within (deg) | moving stones | "
              "modes | solve (s) |",
              "|---|---|---|---|---|---|---|---|---|"]
    for t, e in data["directions"].items():
        for fr, x in e["by_friction"].items():
            m = x["mechanism"] or {}
            cone = (x.get("cone_bracket") or {}).get("angle_deg")
            cone = "—" if not cone or cone[1] is None else f"{cone[0]:.1f}–{cone[1]:.1f}"
            lines.append(f"| {t} | {fr} | {x['status']} | {_fmt(x['multiplier'])} | {_fmt(x['angle_deg'], 1)} | "
                         f"{cone} | {len(m.get('moving_stones', []))} | {', '.join(m.get('modes', []))} | "
                         f"{x['solve_s']:.2f} |")
    lines += ["", f"Exact cone within: the associative multiplier of Coulomb's circular cone lies between this "
              f"{data['facets']}-facet inscribed pyramid's and the circumscribed pyramid's (one more LP); where the "
              "range is wide the stones slip off the load direction: refine with `--facets 16` or `32`.", ""]
    for t, e in data["directions"].items():
        for fr, x in e["by_friction"].items():
            if x.get("message"):
                lines += [f"- {t}, {fr}: {x['message']}"]
    lines += [""] + [f"![mechanism]({f})" for f in figures] + [""]
    return "\n".join(lines)


def limit(case, towards=("+y",), friction=FRICTIONS, out=None, overrides=(), facets: int = la.FACETS,
          settled: bool = False) -> dict:
    """Run the analysis on a case file; writes limit.json, the figures and report.html into
    the analysis folder (``common.output_dir``); returns what limit.json holds. ``settled``:
    the wall after its settling run (``settled_wall``; YADE) instead of as built."""
    from drystone.analyses import common

    frictions = tuple(f for f in FRICTIONS if f in friction)
    if not frictions or set(friction) - set(FRICTIONS):
        raise CaseError(f"--friction: one or both of {list(FRICTIONS)}, got {list(friction)}")
    dirs = directions(towards)  # bad directions fail before anything is read
    if not (isinstance(facets, int) and facets >= 3):
        raise CaseError(f"--facets: an integer >= 3 (the friction pyramid's edges), got {facets!r}")
    out_dir = common.output_dir(case, NAME, out)
    wall = settled_wall(case, overrides, out_dir) if settled else load_wall(case, overrides)
    data, results = analyse(wall, dirs, frictions, facets)
    data.update({"case": str(case), "geometry": "settled" if settled else "as built",
                 "settlement_m": wall.settlement_m, "stones": int((~wall.bodies.fixed).sum()),
                 "fixed_bodies": int(wall.bodies.fixed.sum()), "interfaces": len(wall.ifaces),
                 "corners": int(sum(len(f.polygon) for f in wall.ifaces)), "facets": facets,
                 "mu_range": [float(wall.mu.min()), float(wall.mu.max())] if len(wall.mu) else [0.0, 0.0],
                 "gravity_m_s2": wall.gravity, "ignored": wall.ignored,
                 "units": {"multiplier": "- (horizontal body force / weight)", "angle_deg": "deg",
                           "velocity": "- (normalised: largest interface-corner speed 1)", "solve_s": "s"},
                 "tolerances": {"moving": la.MOVING, "active": la.ACTIVE, "lambda_tol": la.LAMBDA_TOL,
                                "force_tol": la.FORCE_TOL, "relax": la.RELAX, "max_iter": la.MAX_ITER}})
    figs = []
    for (t, fr), r in results.items():
        if r.velocity is not None:
            name = f"mechanism_{t.replace('+', 'p').replace('-', 'm')}_{fr}.png"
            figure(wall, r.velocity, f"{wall.name}: towards {t}, {fr} friction, lambda = {r.multiplier:.4f}",
                   out_dir / name)
            figs.append(name)
    common.write_json(out_dir / "limit.json", data)
    common.write_report(out_dir, f"Limit analysis: {wall.name}", markdown(wall, data, figs),
                        [out_dir / f for f in figs])
    return data


def add_arguments(p) -> None:
    from drystone.analyses import common

    common.add_common_arguments(p)
    p.add_argument("--towards", nargs="+", action="extend", default=None, metavar="DIR",
                   help="load direction(s): +y +x, all, or with a minus sign --towards=-x (argparse reads a "
                        "bare -x as an option); repeatable (default +y)")
    p.add_argument("--friction", nargs="+", default=list(FRICTIONS), choices=FRICTIONS,
                   help="associative and/or coulomb (non-associative, iterated); default both")
    p.add_argument("--facets", type=int, default=la.FACETS,
                   help=f"edges of the friction pyramid at each corner (default {la.FACETS}: exact along the load, "
                        "at most 7.6 %% low between; 4: about twice as fast, up to 29 %% low at 45 deg)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--settled", action="store_true",
                   help="the wall after its settling run (YADE: the case's gravity stages, seconds once the kernels "
                        "are compiled), interfaces by the face test within the settlement")
    g.add_argument("--as-built", action="store_true", help="the wall as built (the default)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a case key")


def main(args) -> int:
    d = limit(args.case, args.towards or ["+y"], args.friction, args.out, args.set, args.facets, settled=args.settled)
    for t, e in d["directions"].items():
        for fr, x in e["by_friction"].items():
            if x["multiplier"] is not None:
                m = x["mechanism"] or {}
                cone = (x.get("cone_bracket") or {}).get("angle_deg")
                cone = f" (cone {cone[0]:.2f}-{cone[1]:.2f})" if cone and cone[1] is not None else ""
                print(f"{t} {fr:11s} lambda {x['multiplier']:.4f}  tilt {x['angle_deg']:.2f} deg{cone}  "
                      f"{len(m.get('moving_stones', []))} stones move ({', '.join(m.get('modes', []))})  "
                      f"{x['solve_s']:.2f} s" + (f"  [{x['status']}]" if x["status"] != "collapse" else ""))
            else:
                print(f"{t} {fr:11s} {x['status']}: {x.get('message', '')}")
    return 0
