"""A study whose runs failed does not look finished: two study processes at once both exited 0
while each printed "2/3 failed", and a report showed an "open (pending)" search as a result.
Now every failed sweep run is recorded (drystone.sweep.FAILED_RUNS), a study that had one
exits 1 with one line naming them (drystone.studies.exit_status), a shape or site study exits 1
when its report is incomplete (drystone/studies/common.py ``main``) and the report's cells
say MISSING. No YADE: the run fails on the lock another process holds, before YADE."""
from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import pytest

from drystone import runner, studies, sweep
from drystone.simulate import FolderLock
from drystone.studies import common as sc
from drystone.studies.site import report as site_report

BOX = {"case": {"name": "cube", "geometry": {"generator": "boxes_on_platform", "damping": 0.5,
                                             "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}]}},
       "stages": [{"type": "gravity", "duration": 0.1, "ramp": 0.05}], "output": {"interval": 0.01}}


@pytest.fixture
def no_failures_yet(monkeypatch):
    monkeypatch.setattr(sweep, "FAILED_RUNS", [])


def test_a_run_another_process_holds_fails_and_the_study_exits_1(tmp_path, no_failures_yet, capsys):
    (tmp_path / "cube.toml").write_text(runner.to_toml(BOX))
    p = tmp_path / "s.toml"
    p.write_text('[sweep]\nname = "s"\ncase = "cube.toml"\n[[runs]]\nname = "a"\n')
    out = tmp_path / "res" / "s" / "a"
    with FolderLock(out):  # the other study process, writing the same run
        res = sweep.run(p, workers=1, results=tmp_path / "res", heartbeat_s=60)
    assert res["failed"] == ["a"] and "another run" in res["runs"]["a"]["error"]
    assert sweep.FAILED_RUNS == [str(out)]
    capsys.readouterr()
    assert studies.exit_status(0) == 1 and studies.exit_status(130) == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: 1 run(s) failed") and str(out) in err


def test_exit_status_of_a_study_without_failures_is_its_own(no_failures_yet):
    assert studies.exit_status(0) == 0 and studies.exit_status(2) == 2


def _study(tmp_path: Path, failed: list, status: dict):
    """sc.main's arguments for a fake study whose run step had ``failed`` runs and whose
    report counts its searches by ``status``."""
    cfg = SimpleNamespace(out_dir=tmp_path)

    def run(cfg, **kw):
        return {"rounds": 1, "runs_run": 2, "runs_reused": 0, "failed": failed, "interrupted": False, "elapsed_s": 6.0}

    def report(cfg):
        (tmp_path / "fake.json").write_text(json.dumps({"status": status, "refused": []}))
        return sc.write_if_changed(tmp_path / "report.md", "# fake\n")

    return ("prog", "doc", {"full": cfg}, lambda c: "plan", run, report, "fake")


@pytest.mark.parametrize("step", ["all", "report"])
def test_an_incomplete_bisection_study_exits_1_naming_what_is_missing(tmp_path, capsys, step):
    args = _study(tmp_path, ["rx/level_2.00"], {"done": 1, "pending": 1, "failed": 1})
    assert sc.main([step], *args) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "1 search(es) pending; 1 search(es) failed" in err and "report.md" in err
    assert ("rx/level_2.00" in err) == (step == "all")


def test_a_complete_bisection_study_exits_0(tmp_path, capsys):
    assert sc.main(["all"], *_study(tmp_path, [], {"done": 3, "pending": 0, "failed": 0})) == 0
    assert capsys.readouterr().err == ""


def test_a_search_without_a_result_reads_missing_not_open():
    for status in ("pending", "failed"):
        text = site_report.bracket_text({"status": status, "bracket": {"done": False, "censored": False}})
        assert text.startswith("**MISSING**") and "open" not in text
    assert site_report.bracket_text({"status": "done", "bracket": {"done": True, "censored": False, "low_g": 0.4,
                                                                   "high_g": 0.5}}) == "(0.4, 0.5]"
