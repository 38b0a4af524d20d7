"""VTK output of a finished run for ParaView, written with meshio (binary XML, zlib-compressed).

``write(run_folder)`` writes ``<run>/vtk/blocks_NNNNN.vtu`` (VTK XML UnstructuredGrid, one
per written sample): every block's faces as polygon cells (a stone of several convex parts:
every part's faces), its corners as points placed as in the snapshots
(drystone/postprocess/snapshots.py ``Frame.place``: x(t) = x_c(t) + R(t) R(0)^T (v - x_c(0)),
in the world frame for a tilt, the platform turned by its tilt), and ``<run>/vtk/blocks.pvd``,
the time series ParaView opens (File > Open blocks.pvd), listing every file with its time.

Arrays (SI units; "initial" is the block file's geometry at t = 0):

- point data ``displacement`` (m, 3 components): x(t) - x(0) of every corner, for Warp By Vector;
- cell data ``block_id``; ``moving`` (1 for a block YADE moves, 0 for the platform and fixed
  blocks); ``rotation`` (rad, 3 components: axis x angle of the block's rotation from its
  initial orientation, including the platform's tilt in the world frame);
  ``centroid_displacement`` (m, 3 components: of the block's centre of mass; the volume
  centroid for blocks YADE does not move).

Why .pvd and not XDMF: each sample is a self-contained .vtu that ParaView (or meshio) opens
alone; VTU holds polygons of any corner count in one cell list, and the collection is a
dozen lines of XML written here (meshio has no .pvd writer).

    python -m drystone.postprocess.vtk results/tilt_seeds/seed_0 [--every 5] [--out DIR] [--platform-frame]
"""
from __future__ import annotations

import json
import sys
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np
from scipy.spatial.transform import Rotation

from drystone.postprocess import snapshots
from drystone.postprocess import summary as summ

#: names of the files written (``NNNNN`` the sample's rank among those written)
PVD_NAME = "blocks.pvd"
SAMPLE_PATTERN = "blocks_{:05d}.vtu"


class Topology:
    """The samples' common mesh: every block's initial corners (points, block by block in id
    order) and faces (polygon cells, grouped as meshio groups them: runs of cells with the
    same number of corners)."""

    def __init__(self, blocks: list[dict]):
        geo = snapshots.stone_geometry(blocks)
        self.ids = sorted(geo)
        self.points0 = {bid: geo[bid][0] for bid in self.ids}  # m
        self.point_slices, cells, cell_block, start = {}, [], [], 0
        for bid in self.ids:
            pts, faces = geo[bid]
            self.point_slices[bid] = slice(start, start + len(pts))
            cells += [np.asarray(f) + start for f in faces]
            cell_block += [bid] * len(faces)
            start += len(pts)
        self.n_points = start
        self.cell_block = np.array(cell_block, np.int32)  # block id of each cell
        self.blocks = []  # meshio cell blocks: ("polygon", (k, corners) array)
        k = 0
        while k < len(cells):
            m = k
            while m < len(cells) and len(cells[m]) == len(cells[k]):
                m += 1
            self.blocks.append(("polygon", np.array(cells[k:m], np.int64)))
            k = m

    def split(self, per_cell: np.ndarray) -> list[np.ndarray]:
        """A cell array cut into meshio's per-cell-block lists."""
        sizes = np.cumsum([len(c) for _, c in self.blocks])[:-1]
        return np.split(per_cell, sizes)


def sample_mesh(topo: Topology, frame: snapshots.Frame, moving: set[int], centroids: dict) -> meshio.Mesh:
    """One sample's mesh with its point and cell data (see the module's docstring)."""
    points = np.empty((topo.n_points, 3))
    rot = np.zeros((len(topo.ids), 3))
    cdisp = np.zeros((len(topo.ids), 3))
    for j, bid in enumerate(topo.ids):
        points[topo.point_slices[bid]] = frame.place(bid, topo.points0[bid])
        rot[j] = Rotation.from_matrix(frame.rotation(bid)).as_rotvec()
        c0 = frame.motion[bid][1] if bid in frame.motion else centroids[bid]
        cdisp[j] = frame.place(bid, c0)[0] - c0
    points0 = np.vstack([topo.points0[bid] for bid in topo.ids])
    rank = np.searchsorted(topo.ids, topo.cell_block)  # each cell's block's row in rot, cdisp
    cell_data = {"block_id": topo.cell_block, "moving": np.isin(topo.cell_block, list(moving)).astype(np.int32),
                 "rotation": rot[rank], "centroid_displacement": cdisp[rank]}
    return meshio.Mesh(points, topo.blocks, point_data={"displacement": points - points0},
                       cell_data={k: topo.split(v) for k, v in cell_data.items()})


def write(run: Path, every: int = 1, world: bool = True, out: Path | None = None) -> Path:
    """Write every ``every``-th recorded sample of a finished run (and the last one); returns the .pvd path.
    Earlier ``blocks_NNNNN.vtu`` files in the output folder are replaced."""
    run = Path(run)
    for f in ("spec.json", "geometry.json", "histories.npz"):
        if not (run / f).is_file():
            raise FileNotFoundError(f"{run}: no {f} (not a finished run folder)")
    if every < 1:
        raise ValueError(f"--every must be >= 1, got {every}")
    blocks = json.loads((run / "geometry.json").read_text())["blocks"]
    h = summ.load_histories(run)
    rows = list(range(0, len(h["t"]), every))
    if rows[-1] != len(h["t"]) - 1:
        rows.append(len(h["t"]) - 1)  # the final state always
    topo = Topology(blocks)
    centroids = snapshots.stone_centroids(blocks)
    moving = {int(i) for i in h["block_ids"]}
    out = Path(out or run / "vtk")
    out.mkdir(parents=True, exist_ok=True)
    for old in list(out.glob("blocks_[0-9][0-9][0-9][0-9][0-9].vt[up]")):
        old.unlink()
    entries = []
    for k, frame in enumerate(snapshots.frames_at(run, [h["t"][i] for i in rows], world=world)):
        name = SAMPLE_PATTERN.format(k)
        meshio.write(out / name, sample_mesh(topo, frame, moving, centroids), file_format="vtu", binary=True)
        entries.append(f'    <DataSet timestep="{frame.t!r}" part="0" file={quoteattr(name)}/>')
    pvd = out / PVD_NAME
    pvd.write_text('<?xml version="1.0"?>\n'
                   '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n  <Collection>\n'
                   + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
    return pvd


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.postprocess.vtk", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a finished run folder (results/...)")
    ap.add_argument("--every", type=int, default=1, help="write every N-th recorded sample (1); the last always")
    ap.add_argument("--out", help="output folder (default <run>/vtk)")
    ap.add_argument("--platform-frame", action="store_true", help="do not rotate a tilted run into the world frame")
    a = ap.parse_args(argv)
    try:
        pvd = write(Path(a.run), a.every, world=not a.platform_frame, out=a.out)
    except (FileNotFoundError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    n = len(list(pvd.parent.glob("blocks_*.vtu")))
    print(f"written {pvd} ({n} samples, coordinates in m, times in s); open it in ParaView")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
