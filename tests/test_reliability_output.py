"""Issue 23: results folders and bad input. A run never deletes what the package did not
write (a user's folder, a sweep's folder, another run's); names do not nest; sweep runs do
not share folders; paths are resolved before YADE sees them; every unreadable input is a
one-line named error with exit 2; a refusal leaves nothing behind; a sweep's workers die
with it. Each test reproduces the issue's fault, then asserts the named error and that
nothing outside the package's own output changed."""
from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import requires_yade
from drystone import cli, paths, runner, sweep
from drystone.model import case as casemod
from drystone.postprocess import summary as summ
from drystone.tomlio import to_toml

BOX = {"generator": "boxes_on_platform", "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}],
       "damping": 0.5}


def _case(name="box", duration=0.1) -> dict:
    return {"case": {"name": name, "geometry": BOX},
            "stages": [{"type": "gravity", "duration": duration, "ramp": duration / 2}],
            "output": {"interval": 0.01}}


def _tree(folder: Path) -> dict:
    """Every file under ``folder`` (hidden ones too) with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _cli(argv, capsys) -> tuple[int, str]:
    """``python -m drystone ARGV`` in this process: exit code and standard error."""
    rc = cli.main([str(a) for a in argv])
    return rc, capsys.readouterr().err


def _one_line_error(rc: int, err: str, *fragments) -> None:
    assert rc == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    for f in fragments:
        assert f in err, err


def _fake_run(out: Path) -> None:
    """A folder as a run writes it (spec.json with the spec's format tag first of all)."""
    out.mkdir(parents=True)
    (out / "spec.json").write_text(json.dumps({"format": "drystone-spec", "version": 2}))
    (out / "summary.json").write_text("{}")


# -- 1. --out a folder the package did not write --------------------------------------------
def test_out_holding_a_users_files_is_refused_and_left_as_it_was(tmp_path, capsys):
    case = tmp_path / "box.toml"
    case.write_text(to_toml(_case()))
    k = tmp_path / "k"
    k.mkdir()
    (k / "notes.txt").write_text("my notes")
    before = _tree(tmp_path)
    rc, err = _cli(["run", case, "--out", k], capsys)
    _one_line_error(rc, err, str(k), "did not write", "notes.txt")
    rc, err = _cli(["run", case, "--out", tmp_path], capsys)  # --out $PWD: the case file's own folder
    _one_line_error(rc, err, str(tmp_path), "box.toml")
    assert _tree(tmp_path) == before  # nothing written, nothing removed, no lock or staging folder


@pytest.mark.parametrize("content, ok", [
    ({}, True),  # an empty folder
    ({"FAILED.txt": "x"}, True),  # a sweep's note of a failed run
    ({"spec.json": json.dumps({"format": "drystone-spec", "version": 2})}, True),  # a run
    ({"spec.json": "{}", "run_info.json": "{}"}, True),  # a run of spec version 1 (no format tag)
    ({"spec.json": "{}"}, False),  # someone else's spec.json
    ({"spec.json": json.dumps({"format": "other"}), "run_info.json": "{}"}, False),
    ({"notes.txt": "x"}, False),
    ({"sweep.json": "{}", "a": None}, False),  # a sweep's folder
    ({"FAILED.txt": "x", "notes.txt": "y"}, False),
])
def test_which_folders_a_run_may_replace(tmp_path, content, ok):
    out = tmp_path / "out"
    out.mkdir()
    for name, text in content.items():
        (out / name).mkdir() if text is None else (out / name).write_text(text)
    if ok:
        runner.check_replaceable(out)
    else:
        with pytest.raises(runner.RunError, match=str(out)):
            runner.check_replaceable(out)


def test_out_that_is_a_file_is_refused(tmp_path):
    f = tmp_path / "f"
    f.write_text("data")
    with pytest.raises(runner.RunError, match="not a folder"):
        runner.check_replaceable(f)
    assert f.read_text() == "data"


# -- 2. a case and a sweep do not replace each other's folder -------------------------------
def test_a_case_named_like_a_sweep_is_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(paths, "RESULTS", tmp_path / "results")
    root = tmp_path / "results" / "twin"
    _fake_run(root / "run_a")
    (root / "sweep.json").write_text(json.dumps({"sweep": "twin", "runs": []}))
    before = _tree(tmp_path / "results")
    with pytest.raises(runner.RunError, match="sweep's folder"):
        runner.run_dict(_case("twin"), tmp_path / "twin.toml", quiet=True)
    assert _tree(tmp_path / "results") == before


def test_a_sweep_named_like_a_case_is_refused(tmp_path):
    results = tmp_path / "results"
    _fake_run(results / "twin")
    (tmp_path / "base.toml").write_text(to_toml(_case()))
    (tmp_path / "s.toml").write_text('[sweep]\nname = "twin"\ncase = "base.toml"\n[[runs]]\nname = "a"\n')
    before = _tree(results)
    with pytest.raises(casemod.CaseError, match="folder of a run"):
        sweep.run(tmp_path / "s.toml", 1, results=results)
    assert _tree(results) == before


# -- 3. sweep runs with colliding folders ---------------------------------------------------
@pytest.mark.parametrize("runs, words", [
    ('[[runs]]\nname = "a"\nout = "o"\n[[runs]]\nname = "b"\nout = "o"\n', "both write into"),
    ('[[runs]]\nname = "a"\nout = "s"\n', "sweep's own folder"),  # the sweep's own folder
    ('[[runs]]\nname = "a"\nout = "."\n', "holds the sweep's own folder"),  # results/ itself
    ('[[runs]]\nname = "a"\nout = "o"\n[[runs]]\nname = "b"\nout = "o/p"\n', "lies inside"),
    ('[[runs]]\nname = "a"\nout = "s/b"\n[[runs]]\nname = "b"\n', "both write into"),  # another run's default
])
def test_colliding_sweep_outputs_are_refused_before_any_run(tmp_path, runs, words):
    (tmp_path / "base.toml").write_text(to_toml(_case()))
    (tmp_path / "s.toml").write_text('[sweep]\nname = "s"\ncase = "base.toml"\n' + runs)
    with pytest.raises(casemod.CaseError, match=words):
        sweep.run(tmp_path / "s.toml", 1, results=tmp_path / "results")
    assert not (tmp_path / "results").exists()


def test_a_sweep_run_may_not_write_into_a_users_folder(tmp_path):
    results = tmp_path / "results"
    (results / "mine").mkdir(parents=True)
    (results / "mine" / "notes.txt").write_text("x")
    (tmp_path / "base.toml").write_text(to_toml(_case()))
    (tmp_path / "s.toml").write_text('[sweep]\nname = "s"\ncase = "base.toml"\n[[runs]]\nname = "a"\nout = "mine"\n')
    with pytest.raises(casemod.CaseError, match="run 'a'.*did not write"):
        sweep.run(tmp_path / "s.toml", 1, results=results)
    assert _tree(results) == {"mine/notes.txt": b"x"}


# -- 6 and 8. unreadable inputs and names: one line, exit 2 ---------------------------------
GOOD = to_toml(_case())
BAD_CASES = {
    "empty": (b"", "missing required key 'geometry'"),
    "not TOML": (b"this is { not toml", "not valid TOML"),
    "nested": (("a = " + "[" * 3000 + "]" * 3000).encode(), "not valid TOML"),
    "nested 40": (("a = " + "[" * 40 + "]" * 40).encode(), "nested more than"),
    "latin-1": ('[case]\nname = "café"\n'.encode("latin-1"), "not UTF-8"),
    "5000 digits": (("[physics]\ngravity = " + "9" * 5000).encode(), "thousands of digits"),
    "4000 digits": (("[physics]\ngravity = " + "9" * 4000).encode(), "integer out of range"),
    "NUL name": (GOOD.replace('name = "box"', 'name = "a\\u0000b"').encode(), "one folder name"),
    "300-character name": (GOOD.replace('name = "box"', f'name = "{"x" * 300}"').encode(), "300 characters"),
    "newline name": (GOOD.replace('name = "box"', 'name = "a\\nb"').encode(), "one folder name"),
    "space name": (GOOD.replace('name = "box"', 'name = "my wall"').encode(), "one folder name"),
    "name with /": (GOOD.replace('name = "box"', 'name = "rx/inner"').encode(), "no '/'"),
    "non-string name": (GOOD.replace('name = "box"', "name = 5").encode(), "'name' must be of type str"),
}


@pytest.mark.parametrize("text, words", BAD_CASES.values(), ids=BAD_CASES)
def test_unreadable_case_files_are_one_line_errors(tmp_path, capsys, text, words):
    p = tmp_path / "c.toml"
    p.write_bytes(text)
    rc, err = _cli(["run", p, "--out", tmp_path / "out"], capsys)
    _one_line_error(rc, err, str(p), words)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["c.toml"]


BAD_BLOCK_FILES = {
    "empty": (b"", "not valid JSON"),
    "not JSON": (b"version = 1", "not valid JSON"),
    "nested": (b"[" * 100000 + b"]" * 100000, "not valid JSON"),
    "latin-1": ('{"a": "café"}'.encode("latin-1"), "not UTF-8"),
    "5000 digits": (b'{"version": ' + b"9" * 5000 + b"}", "thousands of digits"),
}


@pytest.mark.parametrize("text, words", BAD_BLOCK_FILES.values(), ids=BAD_BLOCK_FILES)
def test_unreadable_block_files_are_one_line_errors(tmp_path, capsys, text, words):
    """The run path read a block file twice, the first time without the checks."""
    (tmp_path / "blocks.json").write_bytes(text)
    c = _case()
    c["case"]["geometry"] = "blocks.json"
    (tmp_path / "c.toml").write_text(to_toml(c))
    rc, err = _cli(["run", tmp_path / "c.toml", "--out", tmp_path / "out"], capsys)
    _one_line_error(rc, err, str(tmp_path / "blocks.json"), words)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["blocks.json", "c.toml"]


BAD_SWEEPS = {
    "set is a string": ('[sweep]\ncase = "base.toml"\nset = "string"\n[[runs]]\nname = "a"\n', "'set' must be a list"),
    "override without =": ('[sweep]\ncase = "base.toml"\n[[runs]]\nname = "a"\nset = ["x"]\n', "key=value"),
    "non-string name": ('[sweep]\ncase = "base.toml"\nname = 5\n[[runs]]\nname = "a"\n', "one folder name"),
    "non-string run name": ('[sweep]\ncase = "base.toml"\n[[runs]]\nname = 1\n', "one folder name"),
    "run name with a newline": ('[sweep]\ncase = "base.toml"\n[[runs]]\nname = "a\\nb"\n', "one folder name"),
    "non-string case": ('[sweep]\ncase = 3\n[[runs]]\nname = "a"\n', "'case'"),
    "sweep not a table": ("sweep = 3\n", "[sweep] must be a table"),
    "runs not tables": ('runs = [1]\n[sweep]\ncase = "base.toml"\n', "[[runs]] #1"),
    "grid names too long": ('[sweep]\ncase = "base.toml"\n[grid]\n"case.description" = ["' + "x" * 120 + '"]\n',
                            "one folder name"),
}


@pytest.mark.parametrize("text, words", BAD_SWEEPS.values(), ids=BAD_SWEEPS)
def test_bad_sweep_files_are_one_line_errors(tmp_path, capsys, monkeypatch, text, words):
    monkeypatch.setattr(paths, "RESULTS", tmp_path / "results")
    (tmp_path / "base.toml").write_text(GOOD)
    (tmp_path / "s.toml").write_text(text)
    rc, err = _cli(["sweep", tmp_path / "s.toml"], capsys)
    _one_line_error(rc, err, "s.toml", words)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["base.toml", "s.toml"]


def test_an_override_that_is_no_override(tmp_path, capsys):
    (tmp_path / "c.toml").write_text(GOOD)
    rc, err = _cli(["run", tmp_path / "c.toml", "--set", "casename", "--out", tmp_path / "o"], capsys)
    _one_line_error(rc, err, "'casename' is not of the form key=value")
    rc, err = _cli(["run", tmp_path / "c.toml", "--set", "physics.gravity=" + "9" * 4000, "--out", tmp_path / "o"],
                   capsys)
    _one_line_error(rc, err, "integer out of range")


# -- 10. a refusal after the geometry and time-step checks leaves nothing -------------------
def test_a_refusal_after_the_geometry_is_written_leaves_nothing(tmp_path):
    (tmp_path / "c.toml").write_text(GOOD)
    with pytest.raises(casemod.CaseError, match="step"):  # refused by the time-step check, after geometry.json
        runner.run(tmp_path / "c.toml", ["time.step=1.0"], out_dir=tmp_path / "r" / "box", quiet=True)
    assert list((tmp_path / "r").iterdir()) == []  # no .box.lock, no .box.partial/geometry.json


def test_the_lock_file_goes_with_the_lock(tmp_path):
    out = tmp_path / "box"
    with runner.FolderLock(out) as lock:
        assert lock.path.is_file()
        with pytest.raises(runner.RunError, match="another run"):
            with runner.FolderLock(out):
                pass
    assert list(tmp_path.iterdir()) == []
    with runner.FolderLock(out):  # and it can be taken again
        pass


# -- with YADE ------------------------------------------------------------------------------
@requires_yade
def test_relative_out_from_outside_the_repository(tmp_path):
    """YADE runs in the repository root: a relative --out used to name a folder there."""
    (tmp_path / "c.toml").write_text(GOOD)
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "rel/o", "-q"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "rel" / "o" / "summary.json").is_file()
    assert json.loads((tmp_path / "rel" / "o" / "spec.json").read_text())["out_dir"] == str(tmp_path / "rel" / "o")
    # and a second run replaces the package's own run there (and only that)
    r = subprocess.run([sys.executable, "-m", "drystone", "run", "c.toml", "--out", "rel/o", "-q"], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in (tmp_path / "rel").iterdir()) == ["o"]


@requires_yade
def test_a_full_disk_while_the_summary_is_written_is_a_named_error(tmp_path, monkeypatch):
    out = tmp_path / "box"
    runner.run_dict(_case(), tmp_path / "box.toml", out_dir=out, quiet=True)
    before = _tree(out)

    def full(summary, folder):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(folder / "summary.json"))

    monkeypatch.setattr(summ, "write", full)
    with pytest.raises(runner.RunError, match=r"No space left on device.*unchanged"):
        runner.run(tmp_path / "box.toml", out_dir=out, quiet=True)
    assert _tree(out) == before


@requires_yade
def test_kill_9_of_a_sweep_ends_its_workers_and_their_yade(tmp_path):
    """kill -9 of a sweep's process left its workers running: they started and committed
    further queued runs, then idled with parent 1. Two pool workers, each running a long run
    in its YADE, and a queued run."""
    from test_reliability_run import alive, descendants

    (tmp_path / "base.toml").write_text(GOOD)
    (tmp_path / "s.toml").write_text('[sweep]\nname = "s"\ncase = "base.toml"\n'
                                     '[[runs]]\nname = "long"\nset = ["stages.0.duration=600.0"]\n'
                                     '[[runs]]\nname = "long2"\nset = ["stages.0.duration=600.0"]\n'
                                     '[[runs]]\nname = "queued"\nset = ["stages.0.duration=0.2"]\n')
    results = tmp_path / "results"
    code = ("import sys; from pathlib import Path; from drystone import sweep\n"
            "sweep.run(sys.argv[1], workers=2, results=Path(sys.argv[2]), heartbeat_s=3600)")
    p = subprocess.Popen([sys.executable, "-c", code, str(tmp_path / "s.toml"), str(results)], cwd=paths.ROOT,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    logs = [runner.staging_folder(results / "s" / n) / "log.txt" for n in ("long", "long2")]
    under = {}  # the sweep's workers (forked) and their YADE processes
    try:
        t0 = time.time()
        while not all(f.is_file() and "stage 1/1" in f.read_text() for f in logs):
            assert time.time() - t0 < 240 and p.poll() is None, "the long runs did not start"
            time.sleep(0.2)
        under = descendants(p.pid)
        assert len(under) >= 4 and sum("yade" in c for c in under.values()) >= 2, under  # 2 workers, 2 YADE
        p.kill()
        p.wait()
        t0 = time.time()
        while alive(under) and time.time() - t0 < 20:
            time.sleep(0.2)
        assert not alive(under), "workers or YADE outlived the sweep"
        time.sleep(1.0)
        assert not (results / "s" / "queued").exists()  # no queued run was started or committed
    finally:
        for pid in alive(under):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
