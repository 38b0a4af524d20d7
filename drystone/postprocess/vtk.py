"""VTK output of a finished run for ParaView (plain Python, no VTK library needed).

``write(run_folder)`` writes ``<run>/vtk/blocks_NNNNN.vtp`` (XML PolyData, ASCII): every
block's faces at a recorded sample, placed as in the snapshots (drystone/postprocess/snapshots.py:
x(t) = x_c(t) + R(t) R(0)^T (v - x_c(0)), in the world frame for a tilt), and
``<run>/vtk/blocks.pvd``, the time series ParaView opens (File > Open blocks.pvd). Cell
data per face: ``block_id``, ``moving`` (1 for a free block) and ``displacement_m`` (the
block centroid's displacement from its initial position, m). Coordinates in m, times in s.

    python -m drystone.postprocess.vtk results/tilt_seeds/seed_0 [--every 5] [--out DIR] [--platform-frame]
"""
from __future__ import annotations

import json
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from drystone.postprocess import snapshots
from drystone.postprocess import summary as summ


def _vtp(polys: list[tuple[int, np.ndarray]], moving: set[int], disp: dict[int, float]) -> str:
    """One PolyData piece: every (block id, polygon vertices) as a cell."""
    pts = np.concatenate([p for _, p in polys]) if polys else np.zeros((0, 3))
    sizes = np.array([len(p) for _, p in polys], int)
    ids = [b for b, _ in polys]
    fmt = lambda a, f: " ".join(format(x, f) for x in np.ravel(a))  # noqa: E731
    return "\n".join([
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{len(pts)}" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" '
        f'NumberOfPolys="{len(polys)}">',
        '<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">',
        fmt(pts, ".9g"), "</DataArray></Points>",
        "<Polys>",
        '<DataArray type="Int64" Name="connectivity" format="ascii">', fmt(np.arange(len(pts)), "d"), "</DataArray>",
        '<DataArray type="Int64" Name="offsets" format="ascii">', fmt(np.cumsum(sizes), "d"), "</DataArray>",
        "</Polys>",
        '<CellData Scalars="block_id">',
        '<DataArray type="Int32" Name="block_id" format="ascii">', fmt(ids, "d"), "</DataArray>",
        '<DataArray type="Int32" Name="moving" format="ascii">', fmt([int(b in moving) for b in ids], "d"),
        "</DataArray>",
        '<DataArray type="Float64" Name="displacement_m" format="ascii">',
        fmt([disp.get(b, 0.0) for b in ids], ".9g"), "</DataArray>",
        "</CellData>",
        "</Piece>", "</PolyData>", "</VTKFile>", ""])


def write(run: Path, every: int = 1, world: bool = True, out: Path | None = None) -> Path:
    """Write every ``every``-th recorded sample of a finished run; returns the .pvd path."""
    run = Path(run)
    for f in ("spec.json", "geometry.json", "histories.npz"):
        if not (run / f).is_file():
            raise FileNotFoundError(f"{run}: no {f} (not a finished run folder)")
    if every < 1:
        raise ValueError(f"every must be >= 1, got {every}")
    out = Path(out or run / "vtk")
    out.mkdir(parents=True, exist_ok=True)
    h = summ.load_histories(run)
    ids = [int(i) for i in h["block_ids"]]
    # a stone's faces (a multi-part stone's: every part's), by vertex index: the rigid motion keeps the order
    faces = {bid: f for bid, (_, f) in snapshots.stone_geometry(
        json.loads((run / "geometry.json").read_text())["blocks"]).items()}
    times = h["t"][::every]
    entries = []
    for k, (t, verts, _tilt) in enumerate(snapshots.positions_at(run, list(times), world=world)):
        disp = {b: float(np.linalg.norm(h["pos"][min(k * every, len(h["t"]) - 1), j] - h["pos0"][j]))
                for j, b in enumerate(ids)}
        polys = [(bid, verts[bid][idx]) for bid in sorted(verts) for idx in faces[bid]]
        name = f"blocks_{k:05d}.vtp"
        (out / name).write_text(_vtp(polys, set(ids), disp))
        entries.append(f'<DataSet timestep="{t:.9g}" part="0" file={quoteattr(name)}/>')
    pvd = out / "blocks.pvd"
    pvd.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
                   + "\n".join(entries) + "\n</Collection>\n</VTKFile>\n")
    return pvd


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drystone.postprocess.vtk", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a finished run folder (results/...)")
    ap.add_argument("--every", type=int, default=1, help="write every N-th recorded sample (1)")
    ap.add_argument("--out", help="output folder (default <run>/vtk)")
    ap.add_argument("--platform-frame", action="store_true", help="do not rotate a tilted run into the world frame")
    a = ap.parse_args(argv)
    pvd = write(Path(a.run), a.every, world=not a.platform_frame, out=a.out)
    print(f"written {pvd} ({len(list(pvd.parent.glob('blocks_*.vtp')))} samples); open it in ParaView")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
