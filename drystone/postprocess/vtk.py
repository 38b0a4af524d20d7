"""VTK output of a finished run for ParaView, written with meshio (binary XML, zlib-compressed).

``write(run_folder)`` writes ``<run>/vtk/blocks_NNNNN.vtu`` (VTK XML UnstructuredGrid, one
per written sample): every block's faces as polygon cells (a stone of several convex parts:
every part's faces), its corners as points placed as in the snapshots
(drystone/postprocess/snapshots.py ``Frame.place``: x(t) = x_c(t) + R(t) R(0)^T (v - x_c(0)),
in the world frame for a tilt, the platform turned by its tilt), and ``<run>/vtk/blocks.pvd``,
the time series ParaView opens (File > Open blocks.pvd), listing every file with its time.
Only a complete run is written (drystone/postprocess/runfolder.py); the output folder is
replaced whole, only if it is new, empty or a set this module wrote (``check_out``), and
the new set is written aside and swapped in (the old one kept if writing fails).

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

    python -m drystone.postprocess.vtk results/tilt/seeds/seed_0/runs/towards_+y [--every 5] [--out DIR] [--platform-frame]
"""
from __future__ import annotations

import os
import re
import shutil
import sys
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np
from scipy.spatial.transform import Rotation

from drystone.postprocess import runfolder, snapshots

#: names of the files written (``NNNNN`` the sample's rank among those written)
PVD_NAME = "blocks.pvd"
SAMPLE_PATTERN = "blocks_{:05d}.vtu"
_SAMPLE = re.compile(r"blocks_[0-9]{5}\.vtu")
#: the line in a .pvd that says this module wrote it (and the folder it is in: ``check_out``)
MARK = "<!-- written by drystone.postprocess.vtk: this folder is replaced whole by the next VTK set -->"


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


class VtkError(ValueError):
    """The VTK set cannot be written (one line naming the folder or file; nothing changed)."""


def check_out(out: Path, own: bool = False) -> None:
    """Refuse (VtkError naming the folder and what it holds) to replace ``out`` unless it is
    new, empty or a VTK set this module wrote: a ``blocks.pvd`` carrying ``MARK`` and
    ``blocks_NNNNN.vtu`` files, nothing else. ``own``: ``out`` is the run's own ``vtk``
    folder (inside the package's run folder), where a set written before the mark was
    introduced (the same names, no mark) is the package's too. A user's files are never
    deleted or overwritten (as ``run --out``: drystone/simulate.py ``check_replaceable``)."""
    if not out.exists() and not out.is_symlink():
        return
    if not out.is_dir() or out.is_symlink():
        raise VtkError(f"{out} exists and is not a folder; choose another --out")
    try:
        entries = sorted(p.name for p in out.iterdir())
    except OSError as exc:
        raise VtkError(f"{out}: cannot read the folder: {exc.strerror or exc}") from None
    if not entries:
        return
    foreign = [e for e in entries if e != PVD_NAME and not _SAMPLE.fullmatch(e)]
    try:
        marked = MARK in (out / PVD_NAME).read_text(errors="replace")
    except OSError:
        marked = False
    if foreign or not (marked or own):
        shown = foreign or entries
        raise VtkError(f"{out} holds files this package did not write ({', '.join(shown[:3])}"
                       f"{', ...' if len(shown) > 3 else ''}): a VTK set replaces its folder whole, so it is "
                       "written only into a new or empty folder or one of its own sets; choose another --out")


def write(run: Path, every: int = 1, world: bool = True, out: Path | None = None) -> Path:
    """Write every ``every``-th recorded sample of a finished run (and the last one); returns the .pvd path.

    The run is checked whole first (drystone/postprocess/runfolder.py: NotARun naming the
    file), the output folder too (``check_out``). The new set is written into a hidden
    folder beside ``out`` and swapped in when complete: an earlier set is replaced whole, and
    kept as it was if writing fails (VtkError naming the file, e.g. a full disk)."""
    if every < 1:
        raise ValueError(f"--every must be >= 1, got {every}")
    r = runfolder.load(run)
    h = r.h
    rows = list(range(0, len(h["t"]), every))
    if rows[-1] != len(h["t"]) - 1:
        rows.append(len(h["t"]) - 1)  # the final state always
    out = Path(os.path.abspath(out if out else r.folder / "vtk"))
    check_out(out, own=out.resolve() == (r.folder / "vtk").resolve())
    topo = Topology(r.blocks)
    centroids = snapshots.stone_centroids(r.blocks)
    moving = {int(i) for i in h["block_ids"]}
    stage, old = out.parent / f".{out.name}.vtk-partial", out.parent / f".{out.name}.vtk-old"
    try:
        if old.is_dir() and not out.exists():  # a write stopped between its two renames: the old set back
            os.replace(old, out)
        for d in (stage, old):  # this module's own leftovers of an interrupted write
            shutil.rmtree(d, ignore_errors=True)
        stage.mkdir(parents=True)
        entries = []
        for k, frame in enumerate(snapshots.frames_at(r.folder, [h["t"][i] for i in rows], world=world)):
            name = SAMPLE_PATTERN.format(k)
            meshio.write(stage / name, sample_mesh(topo, frame, moving, centroids), file_format="vtu", binary=True)
            entries.append(f'    <DataSet timestep="{frame.t!r}" part="0" file={quoteattr(name)}/>')
        (stage / PVD_NAME).write_text('<?xml version="1.0"?>\n' + MARK + "\n"
                                      '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                                      "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")
        if out.exists():
            os.replace(out, old)
        os.replace(stage, out)
    except OSError as exc:
        shutil.rmtree(stage, ignore_errors=True)
        if old.is_dir() and not out.exists():
            os.replace(old, out)
        where = str(exc.filename or out).replace(str(stage), str(out))
        raise VtkError(f"{where}: {exc.strerror or exc}; the VTK set in {out} is unchanged") from None
    shutil.rmtree(old, ignore_errors=True)  # the new set is in place
    return out / PVD_NAME


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
    except ValueError as exc:  # NotARun, VtkError, a bad --every
        print(f"error: {exc}", file=sys.stderr)
        return 2
    n = len(list(pvd.parent.glob("blocks_*.vtu")))
    print(f"written {pvd} ({n} samples, coordinates in m, times in s); open it in ParaView")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
