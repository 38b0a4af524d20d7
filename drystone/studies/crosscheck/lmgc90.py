"""Run a case in LMGC90 (parent side): the same case dict this package runs.

``prepare`` resolves the case exactly as ``drystone.runner`` does (``drystone.model.resolve``:
geometry from the block file or generator, materials with the case's overrides, the
stages, collapse thresholds), writes spec.json and the LMGC90 model
(``drystone.studies.crosscheck.translate``); ``run`` starts ``drystone.studies.crosscheck.engine`` in a
subprocess on it (one LMGC90 simulation per process; a Fortran STOP ends only that
process and is reported as ``LMGC90Error`` with the end of its log), then reads the
histories back; ``onset_angle`` dates a tilt collapse with the package's rule
(``drystone.mechanics.collapse.onset``), so both engines are read the same way.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from drystone.model import case as casemod
from drystone.mechanics import collapse
from drystone import paths
from drystone.studies.crosscheck import engine, translate
from drystone.geometry import blockfile as bf
from drystone.model.resolve import resolve
from drystone.model.spec import spec_dict
from drystone.tomlio import to_toml


class LMGC90Error(RuntimeError):
    """The LMGC90 process failed (a Fortran STOP, a crash, a time-out)."""


def prepare(case_dict: dict, folder: Path) -> tuple[dict, dict]:
    """Resolve ``case_dict`` into ``folder`` (case.toml, spec.json, geometry.json, excitation
    samples) and translate its geometry; returns (spec dict, LMGC90 model)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    case_path = folder / "case.toml"
    case_path.write_text(to_toml(case_dict))
    case = casemod.load(case_path)
    spec = spec_dict(resolve(case, str(case_path), folder))
    (folder / "spec.json").write_text(json.dumps(spec, indent=1))
    bs = bf.load(folder / "geometry.json", check_overlaps=False)  # checked by resolve
    model = translate.to_lmgc90(bs, spec["materials"], spec.get("joint_overrides") or {})
    (folder / "lmgc90_model.json").write_text(json.dumps(model))
    return spec, model


def run(case_dict: dict, folder: Path, dt: float, theta: float = 0.5, base: str = "body_force",
        detection: str = engine.DETECTION, interval: float | None = None, timeout_s: float | None = None,
        max_wall_s: float | None = None, quiet: bool = True) -> dict:
    """Run ``case_dict`` in LMGC90 with step ``dt`` (s) in ``folder``; returns
    ``{"spec", "model", "histories", "result", "folder", "log"}``. ``interval``: s between
    recorded samples (default: the case's output interval); ``max_wall_s``: the engine stops
    itself after this many seconds (a partial run, to measure the cost of a heavy case)."""
    folder = Path(folder)
    spec, model = prepare(case_dict, folder)
    for name in (engine.RESULT, engine.HISTORIES):
        (folder / name).unlink(missing_ok=True)
    job = {"model": model, "spec": str(folder / "spec.json"), "folder": str(folder), "out": str(folder),
           "dt": float(dt), "theta": float(theta), "base": base, "detection": detection,
           "interval": float(interval if interval is not None else spec["output"]["interval"]),
           "max_wall_s": max_wall_s}
    job_path = folder / "lmgc90_job.json"
    job_path.write_text(json.dumps(job))
    env = dict(os.environ)
    env["PYTHONPATH"] = str(paths.ROOT) + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    env.setdefault("OMP_NUM_THREADS", "1")  # the wheel's OpenBLAS: one thread, the machine is shared
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    log = folder / "lmgc90_log.txt"
    t0 = time.time()
    with open(log, "w") as out:
        try:
            proc = subprocess.run([sys.executable, "-m", "drystone.studies.crosscheck.engine", str(job_path)], cwd=folder,
                                  env=env, stdout=out, stderr=subprocess.STDOUT, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise LMGC90Error(f"LMGC90 run in {folder} exceeded {timeout_s} s; its log: {log}") from None
    text = log.read_text(errors="replace")
    if not quiet:
        print(text, end="")
    if proc.returncode != 0 or not (folder / engine.RESULT).is_file():
        tail = "\n".join(text.strip().splitlines()[-15:])
        raise LMGC90Error(f"LMGC90 run in {folder} failed (exit code {proc.returncode}; a Fortran STOP or a crash "
                          f"ends the process):\n{tail}")
    result = json.loads((folder / engine.RESULT).read_text())
    result["process_wall_s"] = time.time() - t0
    with np.load(folder / engine.HISTORIES) as z:
        h = {k: z[k] for k in z.files}
    return {"spec": spec, "model": model, "histories": h, "result": result, "folder": str(folder), "log": str(log)}


def onset_angle(run_out: dict) -> dict | None:
    """The collapse angle of an LMGC90 tilt run by the package's rule (the onset of the
    motion that led to the detection: ``drystone.mechanics.collapse.onset`` with the case's onset
    keys), with the detection and the paper's reaction-drop angle; None without a collapse."""
    h, spec, res = run_out["histories"], run_out["spec"], run_out["result"]
    det = res.get("collapse")
    if not det:
        return None
    on = collapse.onset(h["tilt_deg"], h["pos"], h["t"], det["detected_time_s"],
                        spec.get("onset_rate", collapse.RATE_M_PER_DEG),
                        spec.get("onset_window_deg", collapse.WINDOW_DEG))
    tilt_active = np.array([_stage_type(spec, t) == "tilt" for t in h["t"]])
    drop = next((st["params"].get("reaction_drop") for st in spec["stages"]
                 if st["type"] == "tilt" and st["params"].get("until_collapse")), collapse.REACTION_DROP)
    rd = collapse.reaction_drop(h["t"][1:], h["tilt_deg"][1:], h["reaction_N"][1:], res["weight_free_N"],
                                tilt_active[1:], drop)
    out = {"angle_deg": on["angle_deg"] if on else det["detected_angle_deg"],
           "onset_block": int(h["block_ids"][on["index"]]) if on else None,
           "detected_angle_deg": det["detected_angle_deg"], "criterion": det["criterion"],
           "reaction_drop_angle_deg": rd["angle_deg"], "first_blocks": det["first_blocks"]}
    return out


def _stage_type(spec: dict, t: float) -> str:
    for st in spec["stages"]:
        if t < st["end"]:
            return st["type"]
    return spec["stages"][-1]["type"]


def load(folder: Path) -> dict:
    """Read a finished LMGC90 run back from its folder (``run``'s return value without the
    log): histories (``t``, ``tilt_deg``, ``pos`` (n, free blocks, 3) centres of inertia in
    the platform frame, ``frame`` (n, free blocks, 3, 3), ``reaction_N``, ``base_disp``,
    ``block_ids``), the engine's result, the spec and the model."""
    folder = Path(folder)
    if not (folder / engine.RESULT).is_file():
        raise FileNotFoundError(f"{folder}: no {engine.RESULT}: not a finished LMGC90 run")
    with np.load(folder / engine.HISTORIES) as z:
        h = {k: z[k] for k in z.files}
    return {"spec": json.loads((folder / "spec.json").read_text()),
            "model": json.loads((folder / "lmgc90_model.json").read_text()), "histories": h,
            "result": json.loads((folder / engine.RESULT).read_text()), "folder": str(folder)}
