"""A finished run's folder, as the post-processing reads it (report, VTK): what makes it
complete, checked before anything is drawn or written.

A complete run has summary.json (written last: the marker of a complete run), spec.json,
geometry.json and histories.npz, each readable and holding what the post-processing uses:

- summary.json and spec.json: JSON objects; the summary with its ``name`` and ``run``
  (``steps``, ``simulated_time_s``); the spec with ``gravity`` and ``stages`` (each with its
  ``start`` and ``end``, s, and ``params``);
- geometry.json: a JSON object whose ``blocks`` each have an ``id`` and ``vertices`` or ``parts``;
- histories.npz: a readable archive with the time ``t`` (at least one sample) and the moving
  blocks' ``block_ids``, ``pos``/``quat`` per sample and ``pos0``/``quat0``, of matching shapes.

Anything else (a run stopped before its summary, an empty ``{}`` summary, a truncated or
corrupt archive, a geometry that is not JSON) is ``NotARun``, whose one-line message names
the file and what is wrong; nothing is written.
"""
from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drystone.postprocess import summary as summ

#: the files a complete run has (summary.json last: the marker of a complete run)
RUN_FILES = ("summary.json", "spec.json", "geometry.json", "histories.npz")
#: arrays of histories.npz the post-processing reads
HISTORY_ARRAYS = ("t", "tilt_deg", "block_ids", "pos", "quat", "pos0", "quat0")


class NotARun(ValueError):
    """The folder is not a complete run (the message names it and what is missing)."""


@dataclass
class Run:
    """A complete run's contents, each file read once."""
    folder: Path
    summary: dict
    spec: dict
    blocks: list
    h: dict


def _json_object(p: Path, what: str) -> dict:
    try:
        data = json.loads(p.read_text())
    except (ValueError, OSError, RecursionError) as exc:
        why = getattr(exc, "strerror", None) or ("not JSON" if isinstance(exc, ValueError) else "unreadable")
        raise NotARun(f"{p}: not a run's {what} ({why})") from None
    if not isinstance(data, dict):
        raise NotARun(f"{p}: not a run's {what} (not a JSON object)")
    return data


def _need(p: Path, ok: bool, what: str) -> None:
    if not ok:
        raise NotARun(f"{p}: incomplete run: {what}; run the case again into this folder")


def check_files(run_dir: Path) -> Path:
    """``run_dir`` if it is a folder holding every file of ``RUN_FILES``, else NotARun naming
    it and the missing file."""
    d = Path(run_dir)
    if not d.is_dir():
        raise NotARun(f"{d}: no such folder")
    for name in RUN_FILES:
        if not (d / name).is_file():
            raise NotARun(f"{d} is not a complete run (no {name}): run a case into it first "
                          f"(python -m drystone run CASE --out {d})")
    return d


def load(run_dir: Path) -> Run:
    """Read and check a complete run (the module's docstring); NotARun otherwise."""
    d = check_files(run_dir)
    summary = _json_object(d / "summary.json", "summary.json")
    r = summary.get("run")
    _need(d / "summary.json", "name" in summary and isinstance(r, dict)
          and all(isinstance(r.get(k), (int, float)) for k in ("steps", "simulated_time_s")),
          "no name, run.steps or run.simulated_time_s")
    spec = _json_object(d / "spec.json", "spec.json")
    stages = spec.get("stages")
    _need(d / "spec.json", isinstance(stages, list) and bool(stages), "no stages")
    _need(d / "spec.json", all(isinstance(s, dict) and isinstance(s.get("start"), (int, float))
                               and isinstance(s.get("end"), (int, float)) and isinstance(s.get("params"), dict)
                               for s in stages),
          "a stage without its start and end times or params")
    _need(d / "spec.json", isinstance(spec.get("gravity"), (int, float)), "no gravity")
    geo = _json_object(d / "geometry.json", "geometry.json")
    blocks = geo.get("blocks")
    _need(d / "geometry.json", isinstance(blocks, list) and bool(blocks)
          and all(isinstance(b, dict) and "id" in b and ("vertices" in b or "parts" in b) for b in blocks),
          "no blocks, or a block without id and vertices")
    return Run(d, summary, spec, blocks, histories(d))


def histories(run_dir: Path) -> dict:
    """histories.npz (``summary.load_histories``) checked: NotARun naming the file if it
    cannot be read (truncated, corrupt, not an archive) or lacks an array of HISTORY_ARRAYS."""
    p = Path(run_dir) / "histories.npz"
    try:
        h = summ.load_histories(p.parent)
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zipfile.LargeZipFile) as exc:
        raise NotARun(f"{p}: unreadable ({type(exc).__name__}: {str(exc)[:120] or 'truncated'}); "
                      "run the case again into this folder") from None
    missing = [k for k in HISTORY_ARRAYS if k not in h]
    _need(p, not missing, "no " + ", ".join(missing))
    n, m = len(h["t"]), len(h["block_ids"])
    _need(p, n >= 1, "no sample")
    _need(p, np.shape(h["pos"]) == (n, m, 3) and np.shape(h["quat"]) == (n, m, 4)
          and np.shape(h["pos0"]) == (m, 3) and np.shape(h["quat0"]) == (m, 4),
          "arrays of mismatched shapes")
    return h
