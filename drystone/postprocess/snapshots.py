"""Snapshots of the blocks at chosen times, rendered without a display (matplotlib Agg).

Each moving block is drawn at a recorded sample from its initial vertices (geometry.json),
its displacement and rotation: x(t) = x_c(t) + R(t) R(0)^T (v - x_c(0)). Non-moving blocks are
drawn where they are. With ``world=True`` a tilted run is drawn in the world frame (the
platform rotated by its tilt), as the paper's Figure 12.
"""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from drystone.mechanics import rotations  # noqa: E402
from drystone.geometry import polyhedron as ph  # noqa: E402
from drystone.model.loading import LoadProgramme, Stage  # noqa: E402
from drystone.postprocess import summary as summ  # noqa: E402
from drystone.model.spec import stage_type  # noqa: E402


def block_faces(vertices: np.ndarray) -> list[np.ndarray]:
    """Polygons (ordered vertices) of the convex hull's faces (coplanar triangles merged)."""
    return [vertices[idx] for idx in ph.faces(vertices)[2]]


def stone_geometry(blocks) -> dict:
    """{block id: (points (n, 3) m, faces)} of a block file's or spec's blocks: a convex
    block's vertices and hull faces; a stone of several ``parts`` every part's vertices in
    part order and each part's faces (index arrays into those points, so that a rigid
    motion of the points moves the faces)."""
    out = {}
    for b in blocks:
        parts = [np.asarray(p, float) for p in b.get("parts", [b.get("vertices")])]
        faces, offset = [], 0
        for p in parts:
            faces += [idx + offset for idx in ph.faces(p)[2]]
            offset += len(p)
        out[b["id"]] = (np.vstack(parts), faces)
    return out


def positions_at(out: Path, times: list[float], world: bool = True) -> list[tuple[float, dict]]:
    """(sample time, {block id: vertices (n, 3)}, tilt deg) at the samples nearest to
    ``times``; a multi-part stone's vertices are its parts' (``stone_geometry``)."""
    out = Path(out)
    spec = json.loads((out / "spec.json").read_text())
    geo = {bid: v for bid, (v, _) in stone_geometry(json.loads((out / "geometry.json").read_text())["blocks"]).items()}
    h = summ.load_histories(out)
    prog = LoadProgramme([Stage(stage_type(s), s["start"], s["end"], s["params"]) for s in spec["stages"]
                          if stage_type(s) != "excitation"], spec["gravity"])
    ids = [int(i) for i in h["block_ids"]]
    r0 = rotations.to_matrix(h["quat0"])
    frames = []
    for t in times:
        i = int(np.argmin(np.abs(h["t"] - t)))
        r = rotations.to_matrix(h["quat"][i])
        verts = {}
        for bid, v in geo.items():
            if bid in ids:
                j = ids.index(bid)
                v = h["pos"][i, j] + (v - h["pos0"][j]) @ (r[j] @ r0[j].T).T
            verts[bid] = prog.to_world(h["t"][i], v) if world else v
        frames.append((float(h["t"][i]), verts, float(h["tilt_deg"][i])))
    return frames


def render(out: Path, times: list[float], path: Path, world: bool = True, elev: float = 15, azim: float = -60,
           titles: list[str] | None = None, frame_on_first: bool = False) -> Path:
    """One panel per time; moving blocks in stone colour, fixed ones grey, platform dark.
    The axes span every frame's blocks, or with ``frame_on_first`` the first frame's (so
    that stones thrown far after a collapse do not shrink the wall to a dot)."""
    out = Path(out)
    blocks = json.loads((out / "geometry.json").read_text())["blocks"]
    roles = {b["id"]: b["role"] for b in blocks}
    faces = {bid: f for bid, (_, f) in stone_geometry(blocks).items()}
    frames = positions_at(out, times, world)
    framed = frames[:1] if frame_on_first else frames
    allv = np.vstack([v for _, verts, _ in framed for bid, v in verts.items() if roles[bid] != "platform"])
    lo, hi = allv.min(axis=0), allv.max(axis=0)
    span = (hi - lo).max()
    mid = 0.5 * (lo + hi)
    n = len(frames)
    fig = plt.figure(figsize=(4.2 * n, 4.2))
    for k, (t, verts, tilt) in enumerate(frames):
        ax = fig.add_subplot(1, n, k + 1, projection="3d")
        for bid, v in verts.items():
            colour = {"platform": "0.35", "fixed": "0.7"}.get(roles[bid], "#d9b38c")
            ax.add_collection3d(Poly3DCollection([v[idx] for idx in faces[bid]], facecolor=colour, edgecolor="k",
                                                 linewidths=0.3, alpha=1.0))
        for d, setl in enumerate((ax.set_xlim, ax.set_ylim, ax.set_zlim)):
            setl(mid[d] - 0.55 * span, mid[d] + 0.55 * span)
        ax.view_init(elev=elev, azim=azim)
        ax.set_axis_off()
        ax.set_title(titles[k] if titles else f"t = {t:.2f} s, tilt {tilt:.2f} deg", fontsize=9, y=0.92)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.95, wspace=0)
    fig.savefig(path, dpi=110)
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
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
