"""What every analysis shares: its output folder, its command-line arguments, its JSON and
report, running rounds of runs as sweeps, the record override, and THE one reduction of a
finished run folder to its outcome (``outcome``: collapsed? which stones? largest
residual?), used by every analysis and study.

The collapse criterion (``outcome``; docs/physics.md, "Collapse of a stone"): a free stone has
collapsed when, at the end of the run, relative to where it stood at the end of the last
gravity stage (the settlement under its own weight is no collapse; t = 0 without one), in
the platform frame (x along the wall, y out of plane, z up):

* it left the model (drystone/mechanics/stability.py ``ModelRegion``: fell off the platform
  or was thrown away; summary.json ``run.left_model``), or
* it fell: its centroid dropped by more than half its height ``H`` (u_z < -H/2), or
* it overturned: its own vertical axis leans by more than its tipping angle in that
  direction, atan(w / (H/2)), with w = |cos phi| L/2 + |sin phi| D/2 the half-width of its
  bounding box (length L along x, depth D along y) in the direction phi the axis leans
  towards: the angle at which its centroid passes over the edge it rocks on, or
* it was pushed out of the wall: its centroid moved out of plane by more than half its
  depth (|u_y| > D/2): it no longer stands over the bed it was built on.

Residual displacements and rotations short of these are damage, not collapse
(``largest_residual_m``, ``largest_out_of_plane_m``: the damage states are thresholds on
them). A stone that slid along the wall (in plane) by more than half its length without
any of the above is listed in ``in_plane_sliding``, not collapsed (an end stone walking
along the wall under an out-of-plane shaking has not fallen). Stone dimensions are those
of the stone's bounding box at t = 0 (for a multi-part stone, of all its parts).

The paper comparisons keep the paper's own reading of collapse, named as such
(drystone/studies/sacsayhuaman/analysis.py ``COLLAPSE``; the reaction-drop angle of a tilt).
"""
from __future__ import annotations

import hashlib
import json
import os
import re
import time
from pathlib import Path

from drystone.mechanics import collapse as collapse_rule
from drystone.model import case as casemod

#: the file that marks a folder as an analysis's output (written when the folder is made)
MARKER = ".drystone-analysis"

#: the collapse criterion in one line (reports and JSON quote it)
CRITERION = collapse_rule.RULE


# -- folders and arguments --------------------------------------------------------------

def case_name(case_path) -> str:
    """The case's name (its [case] name, or the file's stem): the default results folder."""
    c = casemod.load(case_path)
    return c["case"]["name"]


def output_dir(case_path, analysis: str, out=None) -> Path:
    """The folder an analysis writes into: ``out`` if given, else
    results/<case name>/<analysis>/ (or results/<case name>.analyses/<analysis>/ when
    results/<case name> is the folder of a run of the case, which a later ``drystone run``
    would replace whole). Created, with its marker; refuses (CaseError) a folder that holds
    files the package did not write (never deletes or overwrites a user's files)."""
    from drystone import paths
    from drystone.simulate import is_run_folder

    if out is not None:
        d = Path(out).expanduser().resolve()
    else:
        parent = paths.RESULTS / case_name(case_path)
        if is_run_folder(parent):
            parent = parent.with_name(parent.name + ".analyses")
        d = parent / analysis
    if d.exists() and not d.is_dir():
        raise casemod.CaseError(f"{d} exists and is not a folder: give another --out")
    if d.is_dir() and any(d.iterdir()) and not (d / MARKER).is_file():
        from drystone.simulate import is_run_folder as run_folder

        what = "the folder of a run" if run_folder(d) else "a folder this package did not write"
        raise casemod.CaseError(f"{d} is {what}: an analysis writes only into a new or empty folder or one of its "
                                "own; give another --out")
    d.mkdir(parents=True, exist_ok=True)
    m = d / MARKER
    if not m.is_file():
        m.write_text(json.dumps({"analysis": analysis}) + "\n")
    return d


def add_common_arguments(p) -> None:
    """``case`` positional, ``--out DIR``, ``--workers N``, ``--dask ADDRESS|local``."""
    p.add_argument("case", help="case file (TOML)")
    p.add_argument("--out", metavar="DIR", default=None,
                   help="output folder (default results/<case name>/<analysis>/)")
    p.add_argument("--workers", type=int, default=None, help="parallel runs (default: number of cores)")
    p.add_argument("--dask", metavar="ADDRESS", default=None,
                   help="run on a Dask scheduler (tcp://host:8786), or 'local' for a LocalCluster")


def backend_of(args) -> tuple[str, str | None]:
    """(backend, address) from the common arguments."""
    return ("dask", args.dask) if getattr(args, "dask", None) else ("local", None)


def safe_name(text: str) -> str:
    """A readable, file-system-safe run-name part: a path becomes its stem."""
    s = str(text)
    if "/" in s or "\\" in s or Path(s).suffix:
        s = Path(s).stem
    s = re.sub(r"[^A-Za-z0-9_.+-]", "_", s).strip("._")[:80]  # run names: at most 100 characters
    return s if s and s[0] not in "+-" else f"r{s}"


def number_tag(x: float) -> str:
    """A number as it appears in run names (0.25 -> "0.25", 1.0 -> "1")."""
    return f"{float(x):.6g}"


# -- JSON and reports -------------------------------------------------------------------

def file_sha256(path) -> str | None:
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def provenance(case_path=None, overrides=()) -> dict:
    """Case file and its SHA-256, overrides, package and library versions, git commit, date."""
    from drystone import provenance as prov

    if case_path is None:
        import datetime

        import drystone
        return {"drystone_version": drystone.__version__, "git": prov.git_commit(),
                "date_utc": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
    p = {k: v for k, v in prov.collect(case_path, {}, list(overrides)).items() if k != "case_text"}
    p["case_sha256"] = file_sha256(case_path)
    return p


def write_text(path, text: str) -> Path:
    """Write ``text`` aside and rename it into place (drystone/atomic.py), creating its folder."""
    from drystone import atomic

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic.write_text(path, text)
    return path


def write_json(path, data: dict, *, case=None, overrides=()) -> Path:
    """Write ``data`` as JSON atomically (no NaN or Infinity: a ValueError names the key),
    with ``"provenance"`` added (``provenance``: of ``case``, else of ``data["case"]`` when
    that is a file)."""
    case = case if case is not None else data.get("case")
    if case is not None and not Path(str(case)).is_file():
        case = None
    out = dict(data)
    out["provenance"] = provenance(case, overrides)
    try:
        text = json.dumps(out, indent=1, allow_nan=False, default=_jsonable)
    except ValueError:
        raise ValueError(f"{path}: non-finite numbers in the analysis result; not written") from None
    return write_text(path, text + "\n")


def _jsonable(x):
    import numpy as np

    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (np.floating,)):
        return float(x)
    if isinstance(x, (np.ndarray,)):
        return x.tolist()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


def write_report(out_dir, title: str, markdown: str, figures=()) -> Path:
    """``out_dir``/report.html: one self-contained page of ``markdown`` (images of the
    folder embedded; ``figures`` not referenced in the text are appended); report.md beside it."""
    from drystone.postprocess import markdown as md

    out_dir = Path(out_dir)
    text = markdown if markdown.lstrip().startswith("#") else f"# {title}\n\n{markdown}"
    for f in figures:
        name = Path(f).name
        if name not in text:
            text += f"\n\n![{name}]({name})\n"
    write_text(out_dir / "report.md", text)
    return write_text(out_dir / "report.html", md.html_page(text, out_dir, title))


# -- the case's stages, its excitation and its record ---------------------------------------

#: the gravity stage added to a case that has none (s)
GRAVITY = {"type": "gravity", "duration": 1.0, "ramp": 0.5}
#: the stages added after them to shake a case that has no excitation stage: the record out of
#: plane, then a rest until the motion has died out (as cases/sacsayhuaman/record.toml: the
#: kinetic energy of the free stones below W x 1e-8 m for 1.5 s), at most REST_S
REST_S = 10.0
REST = {"type": "rest", "duration": REST_S, "until_kinetic_below_per_weight": 1e-8, "settle_window": 1.5}


def stages_before(case_path, overrides=()) -> list[dict]:
    """The case's stages before its first tilt or excitation stage, as written (with the
    ``overrides``), with a gravity stage (``GRAVITY``) first if they have none: what a tilt
    or a shaking added by an analysis starts from."""
    from drystone import inputfiles

    raw = inputfiles.load_toml(Path(case_path), casemod.CaseError, "case file")
    raw = casemod.apply_overrides(raw, list(overrides), str(case_path))
    pre = []
    for st in raw.get("stages", []):
        if st.get("type") in ("tilt", "excitation"):
            break
        pre.append(dict(st))
    if not any(st.get("type") == "gravity" for st in pre):
        pre.insert(0, dict(GRAVITY))
    return pre


def record_value(record, where: str = "case") -> str:
    """A record as a case's ``record`` key takes it: a catalogue name, a FEMA P695 id
    ('fema:12a', ASSUMED stand-in), or a file made absolute; CaseError when it is none."""
    from drystone.motions import catalogue, fema

    r = str(record)
    if r in catalogue.names():
        return r
    if fema.parse_id(r):
        try:
            return fema.canonical_id(fema.entry(r))
        except (KeyError, fema.FemaDataMissing) as exc:
            raise casemod.CaseError(f"{where}: record {exc.args[0] if isinstance(exc, KeyError) else exc}") from None
    p = Path(r).expanduser()
    if not p.is_file():
        raise casemod.CaseError(f"{where}: record {r!r} is neither a file, a FEMA P695 id (fema:12a) nor a "
                                f"catalogue name ({', '.join(catalogue.names())})")
    return str(p.resolve())


def shaking_override(case_path, record, direction: str = "y", overrides=()) -> tuple[list[str], int]:
    """For a case without an excitation stage: the ``stages=[...]`` override of its stages
    before any tilt (``stages_before``), then ``record`` along ``direction`` and a rest
    (``REST``); returns (overrides, index of the excitation stage)."""
    from drystone import tomlio

    pre = stages_before(case_path, overrides)
    exc = {"type": "excitation", "motion": "record", "record": record_value(record, str(case_path)),
           "direction": direction}
    return ["stages=" + tomlio.value(pre + [exc, dict(REST)])], len(pre)


def excitation_stage(case_dict: dict, stage=None, where: str = "case") -> int:
    """Index (from 0) of the case's one excitation stage, or of the stage named ``stage``
    (its name or index); CaseError naming the case and the stage otherwise."""
    stages = case_dict["stages"]
    if stage is not None:
        for k, st in enumerate(stages):
            if st.get("name") == stage or str(k) == str(stage):
                if st.get("type") != "excitation":
                    raise casemod.CaseError(f"{where}: stage {stage!r} is a {st.get('type')} stage, not an excitation")
                return k
        names = [st.get("name") or str(k) for k, st in enumerate(stages)]
        raise casemod.CaseError(f"{where}: no stage {stage!r} (stages: {', '.join(names)})")
    found = [k for k, st in enumerate(stages) if st.get("type") == "excitation"]
    if len(found) != 1:
        raise casemod.CaseError(f"{where}: {'no' if not found else len(found)} excitation stage(s); "
                                + ("an analysis that shakes the wall needs one" if not found
                                   else "name the one to use with --stage (its name or index)"))
    return found[0]


#: the keys of an excitation stage that a record replacing its motion keeps
RECORD_STAGE_KEYS = ("type", "name", "direction", "pga_g", "site")


def record_override(case_dict: dict, record, stage=None, where: str = "case") -> list[str]:
    """The ``--set`` override replacing the motion of the case's one excitation stage (or of
    ``stage``) by ``record``, a file (made absolute) or a catalogue name: the whole stage is
    rewritten, keeping its direction, PGA, site and name (a sine's frequency, duration or
    start do not apply to a record; a record's own duration is kept). CaseError naming the
    case and stage when the record is neither a file nor a catalogue name."""
    from drystone import tomlio

    k = excitation_stage(case_dict, stage, where)
    value = record_value(record, f"{where}: stage {k}")
    st = case_dict["stages"][k]
    keep = RECORD_STAGE_KEYS + (("duration",) if st.get("motion") == "record" else ())
    new = {key: st[key] for key in keep if st.get(key) is not None}
    new.update(motion="record", record=value)
    return [f"stages.{k}={tomlio.value(new)}"]


def pga_override(case_dict: dict, pga_g: float, stage=None, where: str = "case") -> list[str]:
    """The override scaling the excitation stage's motion to ``pga_g`` (g)."""
    k = excitation_stage(case_dict, stage, where)
    return [f"stages.{k}.pga_g={float(pga_g)!r}"]


# -- running rounds of runs --------------------------------------------------------------

def run_jobs(case_path, runs: list, root, label: str, common=(), workers=None, backend="local",
             address=None, log=print) -> dict:
    """Run the named runs ``[(name, [overrides])]`` of one case as one sweep into
    ``root``/runs/<name>/ (drystone.sweep: validated first, resumable, finished runs with
    the same fingerprint reused, local pool or Dask); the sweep file is
    ``root``/sweeps/<label>.toml. Prints a progress line (runs done/total, ETA). Returns
    {run name: ``outcome`` of its folder, or {"status": "failed", "error"}}. Raises
    KeyboardInterrupt when the sweep was interrupted."""
    from drystone import sweep, tomlio

    root = Path(root)
    case_path = Path(case_path).resolve()
    if not runs:
        return {}
    names = [n for n, _ in runs]
    if len(set(names)) != len(names):
        raise ValueError(f"run_jobs: duplicate run names in {names}")
    path = root / "sweeps" / f"{safe_name(label)}.toml"
    write_text(path, tomlio.sweep_file("runs", os.path.relpath(case_path, path.parent), [(n, list(o)) for n, o in runs],
                                       list(common), f"written by drystone.analyses ({label}); do not edit"))
    t0 = time.time()
    res = sweep.run(path, workers, backend, address, results=root)
    if res["interrupted"]:
        raise KeyboardInterrupt
    out = {}
    for n, _ in runs:
        st = res["runs"].get(n, {})
        d = root / "runs" / n
        if st.get("status") == "done" or str(st.get("status", "")).startswith("skipped"):
            out[n] = outcome(d)
        else:
            out[n] = {"status": "failed", "error": str(st.get("error", st.get("status", "not run")))[:300],
                      "run_dir": str(d)}
    log(f"[{label}] {len(runs)} run(s) in {time.time() - t0:.0f} s "
        f"({sum(o['status'] == 'done' for o in out.values())} done)")
    return out


# -- THE outcome of a run ----------------------------------------------------------------

def collapse_reasons(extent, u, rotvec) -> tuple[list[str], bool]:
    """The collapse rule for one stone: drystone/mechanics/collapse.py ``stone``."""
    from drystone.mechanics import collapse

    return collapse.stone(extent, u, rotvec)


def outcome(run_dir) -> dict:
    """THE collapse criterion and reduction of a finished run folder (module docstring).

    Returns {"status": "done" | "failed", "run_dir", "collapsed": bool, "collapsed_stones":
    [ids], "why": {id: [reasons: left_model, fell, overturned, out_of_plane]},
    "left_model": [{"block", "time_s"}], "largest_residual_m" (norm, over the stones still
    in the model), "largest_residual_stone", "largest_out_of_plane_m" (|u_y|),
    "largest_out_of_plane_stone", "in_plane_sliding": [ids], "settled" (None without a
    settling rest stage), "end_time_s", "wall_s", and for a run with a tilt stage
    "onset_deg", "reaction_drop_deg", "first_stone", "max_tilt_deg"}. A folder without a
    complete run gives {"status": "failed", "error"}."""
    import numpy as np

    from drystone.model.spec import spec_dict, stage_type
    from drystone.postprocess.summary import load_histories

    d = Path(run_dir)
    try:
        s = json.loads((d / "summary.json").read_text())
        spec = spec_dict(json.loads((d / "spec.json").read_text()))
        h = load_histories(d)
    except Exception as exc:  # noqa: BLE001 - an unreadable run is a failed one, said so
        failed = d / "FAILED.txt"
        err = (failed.read_text(errors="replace").splitlines() or [""])[0] if failed.is_file() else \
            f"{type(exc).__name__}: {exc}"
        return {"status": "failed", "run_dir": str(d), "error": err[:300]}
    from drystone.mechanics import collapse

    t = np.asarray(h["t"], float)
    lm = (s.get("run") or {}).get("left_model") or {}
    left = {int(b["block"]): b.get("time_s") for b in lm.get("blocks") or []}
    for b, r in (s.get("blocks") or {}).items():
        if r.get("motion") == "unbounded" and int(b) not in left:
            left[int(b)] = (r.get("left_model") or {}).get("time_s")

    why, sliding = {}, []
    res_norm, out_plane = {}, {}
    for b, r in collapse.run_stones(spec, h, left).items():
        if r["why"]:
            why[b] = r["why"]
        elif r["in_plane_sliding"]:
            sliding.append(b)
        if r["u_m"] is not None:
            res_norm[b] = float(np.linalg.norm(r["u_m"]))
            out_plane[b] = float(abs(r["u_m"][1]))

    def largest(x):
        if not x:
            return 0.0, None
        b = max(x, key=x.get)
        return x[b], b

    top, top_b = largest(res_norm)
    topy, topy_b = largest(out_plane)
    settle = (s.get("run") or {}).get("settle")
    info = {}
    try:
        info = json.loads((d / "run_info.json").read_text())
    except (OSError, ValueError):
        pass
    o = {"status": "done", "run_dir": str(d), "collapsed": bool(why), "collapsed_stones": sorted(why),
         "why": {str(b): r for b, r in sorted(why.items())},
         "left_model": [{"block": b, "time_s": left[b]} for b in sorted(left, key=lambda b: (left[b] is None,
                                                                                              left[b] or 0, b))],
         "largest_residual_m": top, "largest_residual_stone": top_b,
         "largest_out_of_plane_m": topy, "largest_out_of_plane_stone": topy_b,
         "in_plane_sliding": sorted(sliding),
         "settled": None if settle is None else bool(settle.get("reached")),
         "end_time_s": float(t[-1]) if len(t) else None,
         "wall_s": s.get("wall_time_total_s", info.get("wall_time_s"))}
    if any(stage_type(st) == "tilt" for st in spec["stages"]):
        col = s.get("collapse") or {}
        first = col.get("onset_block")
        if first is None and col.get("first_blocks"):
            first = col["first_blocks"][0]
        o.update(onset_deg=col.get("onset_angle_deg", s.get("collapse_angle_deg")),
                 reaction_drop_deg=s.get("reaction_drop_angle_deg", col.get("reaction_drop_angle_deg")),
                 detected_deg=col.get("detected_angle_deg"), first_stone=first,
                 max_tilt_deg=float(np.max(h["tilt_deg"])) if "tilt_deg" in h and len(h["tilt_deg"]) else None)
    return o
