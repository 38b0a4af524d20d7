"""Snapshots of the blocks at chosen times, rendered without a display (matplotlib Agg).

Each moving block is drawn at a recorded sample from its initial vertices (geometry.json),
its displacement and rotation: x(t) = x_c(t) + R(t) R(0)^T (v - x_c(0)). Non-moving blocks are
drawn where they are. With ``world=True`` a tilted run is drawn in the world frame (the
platform rotated by its tilt), as the paper's Figure 12.

Hidden faces: matplotlib's 3D axes sort whole collections (one per block), not faces, and
drew the platform over the stones standing on it. ``render`` therefore projects the blocks
itself (orthographic, matplotlib's ``elev``/``azim``) and paints 2D polygons: each convex
part's back faces culled, parts ordered back to front by planes that separate them
(``_draw_order``), which is exact for convex solids that do not interpenetrate.
"""
from __future__ import annotations

import heapq
import json
from pathlib import Path
from typing import Callable, NamedTuple

import matplotlib

matplotlib.use("Agg")
import matplotlib.colors  # noqa: E402
import matplotlib.figure  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

from drystone import atomic  # noqa: E402
from drystone.mechanics import rotations  # noqa: E402
from drystone.geometry import polyhedron as ph  # noqa: E402
from drystone.model.loading import LoadProgramme, Stage  # noqa: E402
from drystone.postprocess import summary as summ  # noqa: E402
from drystone.model.spec import stage_type  # noqa: E402

#: dots per inch of the snapshot figures
DPI = 110


def block_faces(vertices: np.ndarray) -> list[np.ndarray]:
    """Polygons (ordered vertices) of the convex hull's faces (coplanar triangles merged)."""
    return [vertices[idx] for idx in ph.faces(vertices)[2]]


def stone_geometry(blocks, by_part: bool = False) -> dict:
    """{block id: (points (n, 3) m, faces)} of a block file's or spec's blocks: a convex
    block's vertices and hull faces; a stone of several ``parts`` every part's vertices in
    part order and each part's faces (index arrays into those points, so that a rigid
    motion of the points moves the faces). With ``by_part`` faces is a list per part."""
    out = {}
    for b in blocks:
        parts = [np.asarray(p, float) for p in b.get("parts", [b.get("vertices")])]
        faces, offset = [], 0
        for p in parts:
            faces.append([idx + offset for idx in ph.faces(p)[2]])
            offset += len(p)
        out[b["id"]] = (np.vstack(parts), faces if by_part else [f for fs in faces for f in fs])
    return out


def stone_centroids(blocks) -> dict:
    """{block id: volume centroid (3,) m} of a block file's blocks (a stone of several parts:
    the parts' centroids weighted by their volumes)."""
    out = {}
    for b in blocks:
        vc = [ph.volume_centroid(np.asarray(p, float)) for p in b.get("parts", [b.get("vertices")])]
        vol = np.array([v for v, _ in vc])
        out[b["id"]] = (vol[:, None] * np.array([c for _, c in vc])).sum(axis=0) / vol.sum()
    return out


class Frame(NamedTuple):
    """One recorded sample: a point v of block ``bid`` at t = 0 (platform frame) is at
    ``to_world(c + R (v - c0))`` with (R, c0, c) = ``motion[bid]`` (moving blocks only;
    the others stay put in the platform frame)."""
    t: float  # s, the sample's time
    tilt_deg: float  # deg, the platform's tilt
    motion: dict  # {block id: (R (3, 3) rotation since t = 0, c0 (3,) m initial centre, c (3,) m centre)}
    to_world: Callable  # (n, 3) platform-frame points -> world (identity with world=False)

    def place(self, bid: int, v) -> np.ndarray:
        """Where the points ``v`` (n, 3) m of block ``bid`` at t = 0 are at this sample."""
        if bid in self.motion:
            rot, c0, c = self.motion[bid]
            v = c + (v - c0) @ rot.T
        return self.to_world(v)

    def rotation(self, bid: int) -> np.ndarray:
        """Block ``bid``'s rotation matrix from t = 0 to this sample (with the tilt in the world frame)."""
        turn = self.to_world(np.eye(3)).T  # the tilt's matrix: its columns are the images of the axes
        return turn @ self.motion[bid][0] if bid in self.motion else turn


def frames_at(out: Path, times: list[float], world: bool = True) -> list[Frame]:
    """The rigid motion of every moving block at the samples nearest to ``times`` (s)."""
    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    h = summ.load_histories(out)
    prog = LoadProgramme([Stage(stage_type(s), s["start"], s["end"], s["params"]) for s in spec["stages"]
                          if stage_type(s) != "excitation"], spec["gravity"])
    ids = [int(i) for i in h["block_ids"]]
    r0 = rotations.to_matrix(h["quat0"])
    frames = []
    for t in times:
        i = int(np.argmin(np.abs(h["t"] - t)))
        r = rotations.to_matrix(h["quat"][i])
        motion = {bid: (r[j] @ r0[j].T, h["pos0"][j], h["pos"][i, j]) for j, bid in enumerate(ids)}
        ti = h["t"][i]
        frames.append(Frame(float(ti), float(h["tilt_deg"][i]), motion,
                            (lambda x, ti=ti: prog.to_world(ti, x)) if world else np.atleast_2d))
    return frames


def positions_at(out: Path, times: list[float], world: bool = True) -> list[tuple[float, dict]]:
    """(sample time, {block id: vertices (n, 3)}, tilt deg) at the samples nearest to
    ``times``; a multi-part stone's vertices are its parts' (``stone_geometry``)."""
    out = Path(out)
    geo = {bid: v for bid, (v, _) in stone_geometry(json.loads((out / "geometry.json").read_text())["blocks"]).items()}
    result = []
    for fr in frames_at(out, times, world):
        result.append((fr.t, {bid: fr.place(bid, v) for bid, v in geo.items()}, fr.tilt_deg))
    return result


#: face colours by role (matplotlib colour specs); a free stone's is STONE_COLOUR
ROLE_COLOURS = {"platform": "0.35", "fixed": "0.7"}
STONE_COLOUR = "#d9b38c"
#: relative brightness of a face turned away from the light and of one facing it (flat shading)
SHADE_RANGE = (0.62, 1.0)


def view_axes(elev: float, azim: float) -> np.ndarray:
    """Rows: the screen's right and up and the direction towards the viewer (unit, world
    frame) for matplotlib's view angles ``elev``, ``azim`` (deg)."""
    e, a = np.radians(elev), np.radians(azim)
    toward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    right = np.array([-np.sin(a), np.cos(a), 0.0])
    return np.array([right, np.cross(toward, right), toward])


def project(points, elev: float, azim: float) -> tuple[np.ndarray, np.ndarray]:
    """Orthographic view of (n, 3) points (m): screen coordinates (n, 2) m and depth (n,) m,
    larger nearer the viewer."""
    p = np.atleast_2d(np.asarray(points, float)) @ view_axes(elev, azim).T
    return p[:, :2], p[:, 2]


def _draw_order(parts: list[dict], toward: np.ndarray) -> list[int]:
    """Back-to-front order of convex parts (painter's algorithm by object, not by face).

    Two parts whose screen boxes overlap are ordered by a plane that separates them: a face
    plane of one with every corner of the other on its outer side (within 2 % of the smaller
    part's size, for touching and slightly overlapping contacts). The part on the viewer's
    side of that plane is drawn later; for disjoint convex solids and an orthographic view
    this is exact. Pairs with no such plane (interpenetrating, or separated only by an
    edge-edge plane) and cycles fall back to the depth of the centroids. The order is a
    topological sort of these constraints, farthest centroid first among the free ones."""
    n = len(parts)
    lo = np.array([p["box"][0] for p in parts])
    hi = np.array([p["box"][1] for p in parts])
    overlap = np.all((lo[:, None] < hi[None]) & (lo[None] < hi[:, None]), axis=2)
    after = [[] for _ in range(n)]  # after[a]: parts drawn after a
    indeg = np.zeros(n, int)
    for a, b in zip(*np.nonzero(np.triu(overlap, 1))):
        tol = 0.02 * min(parts[a]["size"], parts[b]["size"])
        best, sign = 0.0, 0
        for p, q, s in ((a, b, 1), (b, a, -1)):  # planes of p with q outside: q in front of p if n.toward > 0
            gap = (parts[p]["normals"] @ parts[q]["points"].T - parts[p]["offsets"][:, None]).min(axis=1)
            facing = parts[p]["normals"] @ toward
            ok = gap >= -tol
            if np.any(ok) and np.abs(facing[ok]).max() > best:
                k = np.flatnonzero(ok)[np.argmax(np.abs(facing[ok]))]
                best, sign = abs(facing[k]), s * np.sign(facing[k])
        if best > 1e-9:
            first, last = (a, b) if sign > 0 else (b, a)
            after[first].append(last)
            indeg[last] += 1
    depth = np.array([p["depth"] for p in parts])
    ready = [(depth[k], k) for k in range(n) if indeg[k] == 0]
    heapq.heapify(ready)
    done = np.zeros(n, bool)
    order = []
    while len(order) < n:
        if not ready:  # a cycle: break it at its farthest part
            k = min((k for k in range(n) if not done[k]), key=lambda k: depth[k])
            indeg[k] = 0
            ready = [(depth[k], k)]
        _, k = heapq.heappop(ready)
        if done[k]:
            continue
        done[k] = True
        order.append(k)
        for m in after[k]:
            indeg[m] -= 1
            if indeg[m] == 0 and not done[m]:
                heapq.heappush(ready, (depth[m], m))
    return order


def _panel(ax, verts: dict, faces: dict, roles: dict, elev: float, azim: float) -> None:
    """Draw one frame's blocks into the 2D axes ``ax``: every convex part's faces that face
    the viewer (back faces culled), parts back to front (``_draw_order``), flat shaded."""
    axes = view_axes(elev, azim)
    toward = axes[2]
    light = axes[2] + 0.6 * axes[1] - 0.4 * axes[0]
    light /= np.linalg.norm(light)
    parts = []
    for bid, v in verts.items():
        base = np.array(matplotlib.colors.to_rgb(ROLE_COLOURS.get(roles[bid], STONE_COLOUR)))
        for part_faces in faces[bid]:
            polys = [v[idx] for idx in part_faces]
            # Newell's normal of each face (vertices counter-clockwise seen from outside)
            nrm = np.array([np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0) for p in polys])
            nrm /= np.linalg.norm(nrm, axis=1)[:, None]
            pts = v[np.unique(np.concatenate(part_faces))]
            xy, d = project(pts, elev, azim)
            parts.append({"points": pts, "normals": nrm, "polys": polys, "base": base,
                          "offsets": np.array([nn @ p.mean(axis=0) for nn, p in zip(nrm, polys)]),  # n . x on the face
                          "box": (xy.min(axis=0), xy.max(axis=0)), "depth": d.mean(),
                          "size": float(np.ptp(pts, axis=0).max())})
    drawn, colours = [], []
    for k in _draw_order(parts, toward):
        p = parts[k]
        for poly, nrm in zip(p["polys"], p["normals"]):
            if nrm @ toward <= 0:  # a back face: hidden by its own part
                continue
            drawn.append(project(poly, elev, azim)[0])
            colours.append(p["base"] * (SHADE_RANGE[0] + (SHADE_RANGE[1] - SHADE_RANGE[0]) * max(0.0, nrm @ light)))
    ax.add_collection(PolyCollection(drawn, facecolors=colours, edgecolors="k", linewidths=0.3))


def figure(out: Path, times: list[float], world: bool = True, elev: float = 15, azim: float = -60,
           titles: list[str] | None = None, frame_on_first: bool = False) -> matplotlib.figure.Figure:
    """``render``'s figure, not saved (for tests that read its pixels)."""
    out = Path(out)
    blocks = json.loads((out / "geometry.json").read_text())["blocks"]
    roles = {b["id"]: b["role"] for b in blocks}
    geo = stone_geometry(blocks, by_part=True)
    faces = {bid: f for bid, (_, f) in geo.items()}
    frames = [(fr.t, {bid: fr.place(bid, v) for bid, (v, _) in geo.items()}, fr.tilt_deg)
              for fr in frames_at(out, times, world)]
    framed = frames[:1] if frame_on_first else frames
    allv = np.vstack([v for _, verts, _ in framed for bid, v in verts.items() if roles[bid] != "platform"])
    xy = project(allv, elev, azim)[0]
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    pad = 0.08 * (hi - lo).max()
    n = len(frames)
    fig = plt.figure(figsize=(4.2 * n, 4.2), dpi=DPI)
    for k, (t, verts, tilt) in enumerate(frames):
        ax = fig.add_subplot(1, n, k + 1)
        _panel(ax, verts, faces, roles, elev, azim)
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_axis_off()
        ax.set_title(titles[k] if titles else f"t = {t:.2f} s, tilt {tilt:.2f} deg", fontsize=9)
    fig.subplots_adjust(left=0.01, right=0.99, bottom=0.01, top=0.92, wspace=0.02)
    return fig


def render(out: Path, times: list[float], path: Path, world: bool = True, elev: float = 15, azim: float = -60,
           titles: list[str] | None = None, frame_on_first: bool = False) -> Path:
    """One panel per time, a PNG of 4.2 in x 4.2 in per panel at DPI: moving blocks in stone
    colour, fixed ones grey, platform dark, seen from ``elev``, ``azim`` (deg, matplotlib's
    view angles) in an orthographic view with hidden faces removed (``_panel``). The view
    spans every frame's blocks but the platform, or with ``frame_on_first`` the first
    frame's (so that stones thrown far after a collapse do not shrink the wall to a dot)."""
    fig = figure(out, times, world, elev, azim, titles, frame_on_first)
    atomic.savefig(fig, path, dpi=DPI)
    plt.close(fig)
    return Path(path)


def times_at_angles(out: Path, angles: list[float], after: float = 0.5) -> list[float]:
    """Sample times where the platform first reaches each tilt angle (deg); an angle past
    the last tilt gives the last sample (the state after collapse)."""
    h = summ.load_histories(Path(out))
    times = []
    for a in angles:
        i = np.flatnonzero(h["tilt_deg"] >= a - 1e-9)
        times.append(float(h["t"][i[0]]) if len(i) else float(h["t"][-1]))
    return times


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.postprocess.snapshots", description=__doc__)
    ap.add_argument("results", help="a results/<case> folder")
    ap.add_argument("--times", type=float, nargs="*", help="times (s)")
    ap.add_argument("--angles", type=float, nargs="*", help="platform tilts (deg); 999 = the end")
    ap.add_argument("--out", help="PNG path (default <results>/snapshots.png)")
    a = ap.parse_args(argv)
    times = a.times or (times_at_angles(a.results, a.angles) if a.angles else [0.0, 1e9])
    print(render(a.results, times, a.out or Path(a.results) / "snapshots.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


def elevation(block_file: Path, path: Path) -> Path:
    """Front elevation (x-z) of a block file with every block's id, roles shaded and
    control points marked: the numbering at a glance (cf. the paper's Figure 19c)."""
    from matplotlib.patches import Polygon

    d = json.loads(Path(block_file).read_text())
    fig, ax = plt.subplots(figsize=(10, 5))
    for b in d["blocks"]:
        colour = {"platform": "0.35", "fixed": "0.75"}.get(b["role"], "#e8cfa9" if not b.get("blocked_dofs") else "#c9a46b")
        parts = [np.asarray(p, float) for p in b.get("parts", [b.get("vertices")])]
        for k, v in enumerate(parts):  # a stone of several parts: each part's outline, the joints between them thin
            front = v[np.isclose(v[:, 1], v[:, 1].min())][:, [0, 2]]
            c = front.mean(axis=0)
            order = np.argsort(np.arctan2(front[:, 1] - c[1], front[:, 0] - c[0]))
            ax.add_patch(Polygon(front[order], closed=True, facecolor=colour, edgecolor="k" if len(parts) == 1 else "0.5",
                                 lw=0.6 if len(parts) == 1 else 0.3))
        if b["role"] != "platform":
            pts = np.vstack(parts)
            ax.text(*pts[:, [0, 2]].mean(axis=0), str(b["id"]), ha="center", va="center", fontsize=8)
    for cp in d.get("control_points", []):
        ax.plot(cp["position"][0], cp["position"][2], "rv", ms=8)
        ax.text(cp["position"][0], cp["position"][2] + 0.05, cp["name"], color="r", ha="center", va="bottom")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.set_title(f"{d.get('name', '')}: fixed (grey), side blocks with blocked DOFs (dark), control points (red)",
                 fontsize=9)
    fig.tight_layout()
    atomic.savefig(fig, path, dpi=110)
    plt.close(fig)
    return Path(path)
