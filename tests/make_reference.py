"""Regenerate the stored reference histories of tests/test_regression.py. Run by hand, from
the repository root, after a change of results that is intended:

    .venv/bin/python tests/make_reference.py            # every case of CASES
    .venv/bin/python tests/make_reference.py gravity4   # only the named ones

Each case runs on one thread (``drystone.runner.run``, threads=1, in a temporary folder)
and its histories are written, every ``every``-th sample, to
tests/data/reference/<name>.npz: the time axis, the blocks' positions, the kinetic energy
and the normal and tangential force of the named contact, with a JSON string ``meta`` that
records the package commit (and whether the work tree had uncommitted changes, with a
digest of the package's sources), the YADE, numpy and Python versions, the machine, the
time step and the date. The test re-runs the same cases and compares them with these
files (tolerance: tests/tolerances.py, REGRESSION_REL).
"""
from __future__ import annotations

import datetime
import hashlib
import json
import platform
import sys
import tempfile
from pathlib import Path

import numpy as np

from drystone import paths, provenance, runner
from drystone.postprocess import summary as summ

REFERENCE = Path(__file__).resolve().parent / "data" / "reference"

#: the slab of tests/test_excitation.py sliding under a 2 Hz, 1 m/s^2 base sine (mu 0.05):
#: friction stick-slip driven through the excitation path
SINE_SLAB = {
    "case": {"name": "sine_slab",
             "geometry": {"generator": "boxes_on_platform", "mu": 0.05, "damping": 0.8,
                          "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.4, 0.4, 0.04]}]}},
    "stages": [{"type": "gravity", "duration": 0.4, "ramp": 0.2},
               {"type": "excitation", "motion": "sine", "frequency_hz": 2.0, "amplitude": 1.0,
                "direction": "x", "duration": 1.5}],
    "output": {"interval": 0.005, "contacts": [{"name": "0-1", "blocks": [0, 1]}]},
}

#: name -> (case file or case dict, named contact stored, keep every n-th sample)
CASES = {
    "gravity4": (paths.CASES / "gravity4.toml", "1-2", 2),          # 2 s: 183 samples stored
    "settlement4": (paths.CASES / "settlement4.toml", "1-2", 10),   # 7 s: 321 samples
    "sine_slab": (SINE_SLAB, "0-1", 1),                             # 1.9 s: 377 samples
}
FIELDS = ("t", "pos", "kinetic", "fn", "ft")


def sources_digest() -> str:
    """SHA-256 of the package's Python sources: which code wrote a file, even from a work
    tree with uncommitted changes."""
    h = hashlib.sha256()
    for p in sorted(paths.PACKAGE.rglob("*.py")):
        h.update(p.relative_to(paths.PACKAGE).as_posix().encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def run(name: str, workdir: Path) -> tuple[dict, dict]:
    """Run case ``name`` on one thread in ``workdir``; returns (arrays, meta)."""
    case, contact, every = CASES[name]
    out = Path(workdir) / name
    if isinstance(case, dict):
        runner.run_dict(case, Path(workdir) / f"{name}.toml", out_dir=out, threads=1, quiet=True)
    else:
        runner.run(case, out_dir=out, threads=1, quiet=True)
    h = summ.load_histories(out)
    c = h["contacts"][contact]
    arrays = {"t": h["t"], "pos": h["pos"], "kinetic": h["kinetic"], "fn": c["fn"], "ft": c["ft"]}
    arrays = {k: np.asarray(v)[::every] for k, v in arrays.items()}
    info = json.loads((out / "run_info.json").read_text())
    spec = json.loads((out / "spec.json").read_text())
    meta = {"case": name, "contact": contact, "every": every, "threads": info.get("threads"),
            "yade_version": info.get("yade_version"), "dt_s": spec["dt"], "steps": info.get("steps"),
            "git": provenance.git_commit(), "sources_sha256": sources_digest(), "numpy": np.__version__, "python": platform.python_version(),
            "machine": platform.machine(), "processor": platform.processor(),
            "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
    return arrays, meta


def load(name: str) -> tuple[dict, dict]:
    """The stored reference of case ``name``: (arrays, meta)."""
    with np.load(REFERENCE / f"{name}.npz") as z:
        return {k: z[k] for k in FIELDS}, json.loads(str(z["meta"]))


def main(names: list[str]) -> int:
    REFERENCE.mkdir(parents=True, exist_ok=True)
    for name in names or list(CASES):
        with tempfile.TemporaryDirectory() as tmp:
            arrays, meta = run(name, Path(tmp))
        path = REFERENCE / f"{name}.npz"
        np.savez_compressed(path, meta=np.array(json.dumps(meta)), **arrays)
        dirty = " (uncommitted changes)" if meta["git"]["dirty"] else ""
        print(f"{path}: {len(arrays['t'])} samples, {path.stat().st_size / 1e3:.0f} kB, "
              f"commit {meta['git']['commit']}{dirty}, YADE {meta['yade_version']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
