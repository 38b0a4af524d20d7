"""The documentation's runnable blocks run as written, so a snippet cannot go stale.

Every ```sh or ```python block of README.md and docs/*.md with the line
``<!-- runnable -->`` directly above it (tests/docblocks.py) is one test. It runs in a
temporary folder standing for the repository root (``cases/`` and ``data/`` linked in,
read only in effect: every output goes under the folder's own ``results/``): first the
document's earlier ``<!-- file: PATH -->`` blocks are written and its earlier runnable
python blocks run (they make the inputs the block may use, as a reader following the page
has them), then the block itself: a python block as one script, a sh block line by line,
stopping at the first line that fails (the message names it). Each sh line starts with
``.venv/bin/python`` (run with this interpreter; ``-m MODULE`` lines in this process, as ``-m``
runs them: ``_module_in_process``) and a run's ``--out`` is under
``results/``. A finished ``drystone run`` must leave summary.json and histories.npz, a
``drystone report`` its report.html, ``drystone.geometry make`` its block file. A
``drystone run`` of a repository case that an earlier block of the session already ran with
the same options gets a copy of that run's folder (``_RUNS``), checked the same way.

README's first wall (six stones tilted out of plane) must collapse below atan(0.2/0.4) =
26.57 deg, the tilt at which a rigid block of the wall's section (0.4 m deep, 0.8 m tall)
topples; the README says so. A bound, not a tolerance: the joints' compliance lowers the
onset, nothing in the model raises it above the rigid limit, and sliding (atan 0.6 = 31 deg)
comes later.
"""
from __future__ import annotations

import json
import math
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import have_yade
from docblocks import ROOT, Block, blocks, documents

LINKED = ("cases", "data")  # what the blocks read from the repository
TIMEOUT_S = 600


def _runnable() -> list[Block]:
    return [b for doc in documents() for b in blocks(doc) if b.runnable]


RUNNABLE = _runnable()


def _params():
    for b in RUNNABLE:
        marks = []
        if b.lang == "sh" and " drystone run " in f" {b.code}":
            marks.append(pytest.mark.skipif(not have_yade(), reason="YADE is not installed (run make setup)"))
            marks.append(pytest.mark.yade)
        yield pytest.param(b, id=b.where, marks=marks)


def _workdir(tmp_path: Path) -> Path:
    work = tmp_path / "repo"
    work.mkdir()
    for name in LINKED:
        (work / name).symlink_to(ROOT / name, target_is_directory=True)
    return work


def _write_file_block(b: Block, work: Path) -> None:
    target = (work / b.file).resolve()
    # a path through cases/ or data/ resolves into the repository itself: refused, as is one outside
    assert not Path(b.file).is_absolute() and target.is_relative_to(work.resolve()), \
        f"{b.where}: <!-- file: {b.file} --> must name a new file under the repository root, not in {LINKED}"
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(b.code)


def _python(b: Block, work: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", b.code], cwd=work, capture_output=True, text=True, timeout=TIMEOUT_S)


def _check_outputs(argv: list[str], work: Path, where: str) -> None:
    """What a documented command promises to leave behind."""
    mod, rest = (argv[2], argv[3:]) if argv[1] == "-m" else (None, [])
    if mod == "drystone" and rest[:1] == ["run"]:
        out = work / rest[rest.index("--out") + 1]
        summary = json.loads((out / "summary.json").read_text())
        assert (out / "histories.npz").is_file() and summary["run"]["steps"] > 0, where
        if out.name == "my_wall":  # README's first wall: the bound the README states
            assert summary["collapse_angle_deg"] < math.degrees(math.atan(0.2 / 0.4)), summary["collapse_angle_deg"]
    elif mod == "drystone" and rest[:1] == ["report"]:
        assert (work / rest[1] / "report.html").is_file(), f"{where}: no {rest[1]}/report.html"
    elif mod == "drystone.geometry" and rest[:1] == ["make"]:
        assert (work / rest[2]).is_file(), f"{where}: no {rest[2]}"


#: ``drystone run`` lines already run in this session: (case file's bytes, argv without --out)
#: -> the finished output folder. Several documents run the same case with the same options
#: (cases/gravity4.toml: docs/energy.md, paraview.md, reports.md); a later one is given a copy
#: of the first one's folder (the run is deterministic and was checked when it was made), then
#: checked again and its next lines (report, VTK export) run on it as written.
_RUNS: dict = {}


def _run_key(argv: list[str], work: Path):
    """The key of a ``drystone run CASE ... --out DIR`` line whose case is in the repository
    (a file a document wrote itself may differ between documents: never shared)."""
    if argv[1:4] != ["-m", "drystone", "run"] or "--out" not in argv:
        return None
    case = (work / argv[4]).resolve()
    if not any(case.is_relative_to(ROOT / name) for name in LINKED) or not case.is_file():
        return None
    k = argv.index("--out")
    return case.read_bytes(), tuple(argv[:k] + argv[k + 2:])


def _subprocess(argv: list[str], work: Path) -> tuple[int, str]:
    r = subprocess.run(argv, cwd=work, capture_output=True, text=True, timeout=TIMEOUT_S)
    return r.returncode, r.stderr


def _module_in_process(module: str, args: list[str], work: Path) -> tuple[int, str]:
    """``python -m MODULE ARGS`` run as ``-m`` runs it (``runpy.run_module`` as ``__main__``, ``sys.argv``
    set), in this process with ``work`` as the current folder: (exit code, stderr). This process's
    imports and its YADE worker (drystone/simulate.py) serve every line; a fresh interpreter per line
    cost about 2 s of imports and, for a run, 3 s of YADE's start and numba's cache load."""
    import contextlib
    import io
    import os
    import runpy
    import signal
    import traceback
    import warnings

    err = io.StringIO()
    argv, cwd, sigterm = sys.argv, os.getcwd(), signal.getsignal(signal.SIGTERM)
    sys.argv = [module, *args]
    os.chdir(work)
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err), warnings.catch_warnings():
            warnings.filterwarnings("ignore", category=RuntimeWarning, module="runpy")  # a module already imported
            try:
                runpy.run_module(module, run_name="__main__", alter_sys=True)
                rc = 0
            except SystemExit as exc:
                rc = exc.code if isinstance(exc.code, int) else int(exc.code is not None)
                if isinstance(exc.code, str):
                    print(exc.code, file=err)
            except Exception:  # noqa: BLE001 (reported as the line's failure, with its traceback)
                rc = 1
                traceback.print_exc(file=err)
    finally:
        os.chdir(cwd)
        sys.argv = argv
        signal.signal(signal.SIGTERM, sigterm)  # python -m drystone turns SIGTERM into Ctrl-C
    return rc, err.getvalue()


def _sh(b: Block, work: Path) -> None:
    for k, line in enumerate(b.code.splitlines()):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        where = f"{b.doc.relative_to(ROOT)}:{b.line + 1 + k}: {line}"
        argv = shlex.split(line, comments=True)
        assert argv[0] == ".venv/bin/python", f"{where}: runnable commands use the project's interpreter"
        if "--out" in argv:
            assert argv[argv.index("--out") + 1].startswith("results/"), f"{where}: --out goes under results/"
        argv[0] = sys.executable
        key = _run_key(argv, work)
        if key in _RUNS and _RUNS[key].is_dir():
            shutil.copytree(_RUNS[key], work / argv[argv.index("--out") + 1])
        else:
            rc, err = _module_in_process(argv[2], argv[3:], work) if argv[1] == "-m" else _subprocess(argv, work)
            assert rc == 0, f"{where}\nexit {rc}\n{err[-3000:]}"
        _check_outputs(argv, work, where)
        if key is not None and key not in _RUNS:
            _RUNS[key] = work / argv[argv.index("--out") + 1]


@pytest.mark.parametrize("block", list(_params()))
def test_runnable_block(block: Block, tmp_path):
    assert block.lang in ("sh", "python"), f"{block.where}: only sh and python blocks can be runnable"
    work = _workdir(tmp_path)
    for earlier in blocks(block.doc):
        if earlier.line >= block.line:
            break
        if earlier.file:
            _write_file_block(earlier, work)
        elif earlier.runnable and earlier.lang == "python":
            r = _python(earlier, work)
            assert r.returncode == 0, f"{earlier.where} (run before {block.where}) failed:\n{r.stderr[-3000:]}"
    if block.file:
        _write_file_block(block, work)
    if block.lang == "python":
        r = _python(block, work)
        assert r.returncode == 0, f"{block.where}:\n{r.stderr[-3000:]}"
    else:
        _sh(block, work)


def test_the_readme_path_is_runnable():
    """README's first wall: the stones (python), the case file, then run and report (sh)."""
    readme = blocks(ROOT / "README.md")
    assert [b.lang for b in readme if b.runnable] == ["python", "sh"]
    assert any(b.file == "my_wall/wall.toml" for b in readme)
    sh = next(b for b in readme if b.runnable and b.lang == "sh").code
    assert "drystone run my_wall/wall.toml" in sh and "drystone report results/my_wall" in sh
