"""This package's side of the cross-check: the same case dict through ``drystone.runner``
(YADE, the penalty law), at a given K_n."""
from __future__ import annotations

import json
import time
from pathlib import Path

from drystone import runner
from drystone.postprocess import summary as summ


def run(case_dict: dict, folder: Path, threads: int = 1) -> dict:
    """Run ``case_dict`` with ``drystone.runner.run_dict`` into ``folder``/run; returns
    ``{"summary", "histories", "spec", "wall_s", "folder"}``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = folder / "run"
    t0 = time.time()
    s = runner.run_dict(case_dict, folder / "case.toml", out_dir=out, quiet=True, threads=threads)
    wall = time.time() - t0
    spec = json.loads((out / "spec.json").read_text())
    return {"summary": s, "histories": summ.load_histories(out), "spec": spec, "wall_s": wall, "folder": str(out)}
