"""Reliability of what the package writes after a run: VTK sets, report pages, every file
written aside and renamed (drystone/atomic.py), ``make clean``. Each test reproduces a fault
met by a careless user or a full disk (a user's files in ``--out``, a disk that fills up
mid-write, an incomplete or corrupt run folder, a read-only folder, a path with spaces),
then asserts the one-line named error (exit 2) or the right result, and that nothing outside
the package's own output changed. No YADE: the runs are synthetic (tests/test_vtk.py)."""
from __future__ import annotations

import errno
import io
import json
import os
import shlex
import subprocess
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from test_vtk import fake_run  # noqa: E402
from drystone import atomic, cli, paths  # noqa: E402
from drystone.postprocess import report, runfolder, vtk  # noqa: E402


def _tree(folder: Path) -> dict:
    """Every file under ``folder`` (hidden ones too) with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _one_line_error(rc: int, err: str, *fragments) -> None:
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for f in fragments:
        assert f in err, err


def _run(tmp_path: Path, name="run") -> Path:
    fake_run(tmp_path / name, [0.1, 0.0, 0.0], 0.2, times=(0.0, 0.5, 1.0))
    return tmp_path / name


def _enospc(path) -> OSError:
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


# -- VTK: a user's folder, a full disk, a read-only folder -------------------------------------
def test_vtk_out_holding_a_users_files_is_refused_and_left_as_it_was(tmp_path, capsys):
    """The user's blocks_00007.vtu and blocks_00042.vtp were deleted and blocks.pvd overwritten."""
    run = _run(tmp_path)
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("blocks_00007.vtu", "blocks_00042.vtp", "blocks.pvd"):
        (mine / name).write_text(f"the user's {name}")
    before = _tree(tmp_path)
    _one_line_error(vtk.main([str(run), "--out", str(mine)]), capsys.readouterr().err, str(mine), "did not write")
    (mine / "blocks_00042.vtp").unlink()  # only names the package uses, but no mark: still the user's
    before = _tree(tmp_path)
    _one_line_error(vtk.main([str(run), "--out", str(mine)]), capsys.readouterr().err, str(mine), "did not write")
    assert _tree(tmp_path) == before


def test_vtk_replaces_its_own_set_whole(tmp_path):
    """A set the package wrote (in --out or the run's vtk/) is replaced whole: 3 samples, then 2."""
    run = _run(tmp_path)
    for out in (tmp_path / "elsewhere" / "v", None):
        pvd = vtk.write(run, out=out)
        folder = pvd.parent
        assert sorted(p.name for p in folder.iterdir()) == ["blocks.pvd"] + [f"blocks_0000{k}.vtu" for k in range(3)]
        vtk.write(run, every=2, out=out)
        assert sorted(p.name for p in folder.iterdir()) == ["blocks.pvd", "blocks_00000.vtu", "blocks_00001.vtu"]
        assert not [p for p in folder.parent.iterdir() if p.name.startswith(".")]  # no staging left


def test_vtk_on_a_full_disk_keeps_the_earlier_set(tmp_path, monkeypatch, capsys):
    """The earlier set was deleted first, then a traceback, a 0-byte .vtu and the old .pvd."""
    run = _run(tmp_path)
    vtk.write(run)
    before = _tree(tmp_path)
    real, calls = vtk.meshio.write, []

    def fill_up(path, *a, **k):
        calls.append(path)
        if len(calls) == 2:
            Path(path).write_bytes(b"")
            raise _enospc(path)
        return real(path, *a, **k)

    monkeypatch.setattr(vtk.meshio, "write", fill_up)
    _one_line_error(vtk.main([str(run), "--every", "1"]), capsys.readouterr().err,
                    str(run / "vtk" / "blocks_00001.vtu"), "No space left on device", "unchanged")
    assert _tree(tmp_path) == before  # the old set, and no staging folder


def test_vtk_into_a_read_only_folder_is_a_named_error(tmp_path, monkeypatch, capsys):
    """A read-only run folder: a PermissionError traceback. (Run as root, chmod does not stop
    a write: the refusal the system would give is raised where the folder is created.)"""
    run = _run(tmp_path)
    before = _tree(tmp_path)
    real = Path.mkdir

    def read_only(self, *a, **k):
        if self.parent == run:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(self))
        return real(self, *a, **k)

    monkeypatch.setattr(Path, "mkdir", read_only)
    _one_line_error(vtk.main([str(run)]), capsys.readouterr().err, str(run / "vtk"), "Permission denied")
    assert _tree(tmp_path) == before


# -- report and VTK on an incomplete, corrupt or stage-less run --------------------------------
def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


FAULTS = {
    "no summary": (lambda d: (d / "summary.json").unlink(), "no summary.json"),
    "summary {}": (lambda d: (d / "summary.json").write_text("{}"), "summary.json: incomplete run"),
    "summary []": (lambda d: (d / "summary.json").write_text("[]"), "summary.json: not a run's"),
    "spec without stages": (lambda d: (d / "spec.json").write_text(json.dumps({"gravity": 9.81})),
                            "spec.json: incomplete run: no stages"),
    "truncated histories": (lambda d: _truncate(d / "histories.npz"), "histories.npz: unreadable"),
    "corrupt histories": (lambda d: (d / "histories.npz").write_bytes(b"PK\x03\x04" + os.urandom(300)),
                          "histories.npz: unreadable"),
    "histories not an archive": (lambda d: (d / "histories.npz").write_text("hello"), "histories.npz: unreadable"),
    "geometry not JSON": (lambda d: (d / "geometry.json").write_text("{blocks: ["), "geometry.json: not a run's"),
    "geometry without blocks": (lambda d: (d / "geometry.json").write_text("{}"), "geometry.json: incomplete run"),
}


@pytest.mark.parametrize("fault", FAULTS)
@pytest.mark.parametrize("tool", ["report", "vtk"])
def test_an_incomplete_or_corrupt_run_is_refused_naming_the_file(tmp_path, capsys, fault, tool):
    """``vtk`` wrote a full set without summary.json; ``report`` rendered "nan s simulated in
    0 steps" from ``{}``; a spec without stages, a truncated or corrupt histories.npz and a
    geometry.json that is not JSON were tracebacks. Now: one line naming the file, exit 2,
    nothing written."""
    run = _run(tmp_path)
    spoil, words = FAULTS[fault]
    spoil(run)
    before = _tree(tmp_path)
    rc = cli.main(["report", str(run)]) if tool == "report" else vtk.main([str(run)])
    out = capsys.readouterr()
    _one_line_error(rc, out.err, str(run), words)
    assert out.out == "" and _tree(tmp_path) == before


# -- every file written aside: a full disk never leaves a truncated file ----------------------
class _FillingFile(io.StringIO):
    """A file on a disk that fills up after ``room`` characters."""

    def __init__(self, path, room):
        super().__init__()
        self.path, self.room = path, room

    def write(self, s):
        with open(self.path, "ab" if isinstance(s, bytes) else "a") as f:
            f.write(s[: self.room])
        raise _enospc(self.path)


def test_report_on_a_full_disk_leaves_the_old_page_and_names_the_file(tmp_path, monkeypatch, capsys):
    """report.html was left truncated (167 936 of ~250 000 bytes); the message named no file."""
    run = _run(tmp_path)
    (run / "report.html").write_text("the earlier report")
    monkeypatch.setattr(report, "build_html", lambda d: "x" * 250_000)
    before = _tree(tmp_path)
    monkeypatch.setattr(atomic, "open", lambda path, *a, **k: _FillingFile(path, 167_936), raising=False)
    rc = cli.main(["report", str(run)])
    _one_line_error(rc, capsys.readouterr().err, f"{run / 'report.html'}: No space left on device")
    assert _tree(tmp_path) == before  # the old page, no temporary


@pytest.mark.parametrize("writer", ["text", "bytes", "figure"])
def test_atomic_writes_keep_the_old_file_and_name_it(tmp_path, monkeypatch, writer):
    p = tmp_path / ("f.png" if writer == "figure" else "f.txt")
    p.write_text("old")
    fig = plt.figure()
    write = {"text": lambda: atomic.write_text(p, "new" * 1000), "bytes": lambda: atomic.write_bytes(p, b"n" * 3000),
             "figure": lambda: atomic.savefig(fig, p, dpi=50)}[writer]
    real = fig.savefig

    def full(path, *a, **k):  # the figure's writer: part of the file, then the disk is full
        real(path, *a, **k)
        _truncate(Path(path))
        raise _enospc(path)

    monkeypatch.setattr(fig, "savefig", full)
    monkeypatch.setattr(atomic, "open", lambda path, *a, **k: _FillingFile(path, 100), raising=False)
    with pytest.raises(OSError) as exc:
        write()
    plt.close(fig)
    assert exc.value.errno == errno.ENOSPC and exc.value.filename == str(p)
    assert sorted(x.name for x in tmp_path.iterdir()) == [p.name] and p.read_text() == "old"
    monkeypatch.undo()
    assert atomic.write_text(p, "new").read_text() == "new"  # and written when there is room


# -- the Makefile: paths with spaces ----------------------------------------------------------
@pytest.mark.parametrize("target, var", [("vtk", "DIR"), ("report", "DIR"), ("run", "CASE"), ("sweep", "SWEEP"),
                                         ("spectrum", "FILE")])
def test_make_passes_a_path_with_spaces_as_one_argument(target, var):
    """``make vtk DIR="path with space"`` split the path in two (DIR unquoted)."""
    path = "results/a path with  spaces/x"
    r = subprocess.run(["make", "-n", "--no-print-directory", target, f"{var}={path}"],
                       cwd=paths.ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in r.stdout.splitlines() if "-m drystone" in ln]
    assert lines, r.stdout
    assert all(path in shlex.split(ln) for ln in lines), lines


# -- make clean: only what the package wrote ----------------------------------------------------
def test_clean_deletes_only_what_the_package_wrote_and_says_what_it_left(tmp_path, monkeypatch, capsys):
    """``make clean`` deleted results/ wholesale, a user's own files there included."""
    from drystone import clean
    from drystone.model.spec import SPEC_FORMAT

    results, outside = tmp_path / "results", tmp_path / "outside"
    monkeypatch.setattr(paths, "RESULTS", results)
    results.mkdir()
    run = _run(results, "box")  # a run (spec.json with the spec's format tag)
    spec = json.loads((run / "spec.json").read_text())
    (run / "spec.json").write_text(json.dumps(dict(spec, format=SPEC_FORMAT, version=2)))
    vtk.write(run, out=results / "box_vtk")  # a VTK set elsewhere
    (results / ".box.lock").write_text("123")  # leftovers of an interrupted run and write
    (results / ".other.partial").mkdir()
    (results / ".x.tmp-0123abcd.json").write_text("{")
    sweep = results / "sw"
    (sweep / "failed_run").mkdir(parents=True)
    (sweep / "failed_run" / "FAILED.txt").write_text("RunError: ...")
    (sweep / "sweep.json").write_text(json.dumps({"sweep": "sw", "file": "x.toml", "runs": []}))  # before manifests
    study = results / "study"
    study.mkdir()
    atomic.write_text(study / "report.md", "# report")
    atomic.write_text(study / "plan.json", "{}")
    atomic.savefig(plt.figure(), study / "figure.png", dpi=20)
    plt.close("all")
    user = {"README.txt": "my index", "mine/data.csv": "1,2", "study/my notes.md": "mine", "sw/notes.txt": "mine",
            "study/sub/keep.json": "{}"}
    for rel, text in user.items():
        (results / rel).parent.mkdir(parents=True, exist_ok=True)
        (results / rel).write_text(text)
    outside.mkdir()
    (outside / "precious.txt").write_text("not in results")
    (results / "link").symlink_to(outside, target_is_directory=True)
    cache = tmp_path / ".numba_cache"
    (cache / "abc").mkdir(parents=True)
    monkeypatch.setattr(paths, "ROOT", tmp_path)

    assert clean.main([str(results), "--dry-run"]) == 0
    assert (run / "spec.json").is_file() and (study / "report.md").is_file()  # a dry run deletes nothing
    capsys.readouterr()
    assert clean.main([str(results)]) == 0
    printed = capsys.readouterr().out
    left = {str(p.relative_to(results)) for p in results.rglob("*") if p.is_file() or p.is_symlink()}
    assert left == set(user) | {"link"}
    assert all((results / rel).read_text() == text for rel, text in user.items())
    assert (outside / "precious.txt").read_text() == "not in results" and not cache.exists()
    assert "left 6 file(s)" in printed and all(str(results / rel) in printed for rel in user)
    assert not (results / "study" / atomic.MANIFEST).exists()


def test_clean_of_results_holding_only_package_outputs_removes_the_folder(tmp_path, monkeypatch, capsys):
    from drystone import clean

    results = tmp_path / "results"
    monkeypatch.setattr(paths, "RESULTS", results)
    (results / "a" / "b").mkdir(parents=True)
    atomic.write_text(results / "a" / "b" / "report.md", "x")
    removed, left = clean.clean(results, cache=tmp_path / "none")
    assert not results.exists() and left == [] and len(removed) == 2  # report.md and its manifest


def test_make_clean_calls_the_module():
    r = subprocess.run(["make", "-n", "--no-print-directory", "clean"], cwd=paths.ROOT, capture_output=True, text=True)
    assert r.returncode == 0 and "-m drystone.clean" in r.stdout and "rm -rf" not in r.stdout, r.stdout


def test_vtk_after_a_write_stopped_between_its_renames_keeps_the_old_set(tmp_path, monkeypatch, capsys):
    """Killed after the old set was moved aside: the next write puts it back before anything
    else, so a failure of that write still leaves it."""
    run = _run(tmp_path)
    vtk.write(run)
    before = _tree(run / "vtk")
    os.replace(run / "vtk", run / ".vtk.vtk-old")
    monkeypatch.setattr(vtk.meshio, "write", lambda path, *a, **k: (_ for _ in ()).throw(_enospc(path)))
    _one_line_error(vtk.main([str(run)]), capsys.readouterr().err, "No space left on device")
    assert _tree(run / "vtk") == before and sorted(p.name for p in run.iterdir() if p.name.startswith(".")) == []
