"""Sweep runner (drystone/sweep.py): parsing, validation before any run, parallel local
and Dask execution, resumption, failures that do not stop the others."""
import json
from pathlib import Path

import pytest

from conftest import requires_yade
from drystone.model import case as casemod
from drystone import runner, sweep

# one 0.2 m cube settling on a platform for 0.1 s: a run of a few seconds
BASE = {
    "case": {"name": "cube", "geometry": {"generator": "boxes_on_platform", "mu": 0.5, "damping": 0.5,
                                          "kn": 2e8, "kt": 1e8,
                                          "boxes": [{"id": 1, "center_xy": [0.0, 0.0], "size": [0.2, 0.2, 0.2]}]}},
    "stages": [{"type": "gravity", "duration": 0.1, "ramp": 0.05}],
    "output": {"interval": 0.01},
}


def write_sweep(tmp: Path, body: str) -> Path:
    (tmp / "cube.toml").write_text(runner.to_toml(BASE))
    p = tmp / "s.toml"
    p.write_text('[sweep]\nname = "s"\ncase = "cube.toml"\n' + body)
    return p


def test_grid_and_runs_make_named_jobs(tmp_path):
    p = write_sweep(tmp_path, '[grid]\n"contact.kn" = [1e8, 2e8]\n"contact.mu" = [0.3]\n'
                              '[[runs]]\nname = "dem"\nset = ["contact.kn=5e7"]\n')
    name, jobs = sweep.load(p, results=tmp_path / "res")
    assert name == "s"
    assert [j.name for j in jobs] == ["kn_100000000.0-mu_0.3", "kn_200000000.0-mu_0.3", "dem"]
    assert jobs[0].overrides[:2] == ["contact.kn=100000000.0", "contact.mu=0.3"]
    assert all(Path(j.out_dir).parent == tmp_path / "res" / "s" for j in jobs)
    sweep.validate(jobs)  # all three are valid cases


def test_a_file_path_names_its_runs_by_its_stem_and_names_stay_unique(tmp_path):
    """A swept record given as a file path names the run by the file's stem (not the whole
    path with its separators squeezed out); two files of one stem in different folders give
    two names; numbers (0.976) keep their digits."""
    p = write_sweep(tmp_path, '[grid]\n"stages.0.record" = ["../records/far/farfield_01a.txt", '
                              '"/data/near/farfield_01a.txt", "paruro2014"]\n"stages.0.pga_g" = [0.976]\n')
    name, jobs = sweep.load(p, results=tmp_path / "res")
    assert [j.name for j in jobs] == ["record_farfield_01a-pga_g_0.976", "record_farfield_01a-pga_g_0.976-2",
                                      "record_paruro2014-pga_g_0.976"]
    assert jobs[1].params["stages.0.record"] == "/data/near/farfield_01a.txt"  # the override is the path
    assert len({j.out_dir for j in jobs}) == 3


def test_results_table_rows_of_runs_not_finished(tmp_path):
    """A run that failed or is pending has its status and empty values; a folder without a
    complete run reads as failed (the one reduction, analyses.common.outcome)."""
    p = write_sweep(tmp_path, '[[runs]]\nname = "a"\n[[runs]]\nname = "b"\nset = ["contact.mu=0.4"]\n')
    _, jobs = sweep.load(p, results=tmp_path / "res")
    Path(jobs[0].out_dir).mkdir(parents=True)
    rows = sweep.table_rows(jobs, {"a": {"status": "done"}, "b": {"status": "failed"}})
    assert rows[0]["status"].startswith("failed") and rows[0]["collapsed"] == ""
    assert rows[1] == {"run": "b", "overrides": "contact.mu=0.4", "status": "failed", "collapsed": "",
                       "collapsed_stones": "", "largest_residual_mm": "", "onset_deg": ""}


def test_fingerprint_follows_the_inputs_not_the_folder(tmp_path):
    """The same case resolved into two folders has one fingerprint; a changed geometry
    or friction coefficient changes it (sweeps use it to decide what is finished)."""
    p = write_sweep(tmp_path, '[[runs]]\nname = "a"\n')
    prints = []
    for k, over in enumerate([[], [], ["contact.mu=0.4"]]):
        (tmp_path / str(k)).mkdir()
        spec = runner.resolve(casemod.load(tmp_path / "cube.toml", over), "cube", tmp_path / str(k))
        prints.append(runner.fingerprint(spec))
    assert prints[0] == prints[1] != prints[2]
    assert sweep.validate(sweep.load(p, results=tmp_path / "res")[1])["a"] == prints[0]


@pytest.mark.parametrize("body, match", [
    ('[grid]\n"contact.kn" = []\n', "non-empty list"),
    ('[sweep2]\n', "unknown table"),
    ('[[runs]]\nname = "a"\n[[runs]]\nname = "a"\n', "duplicate run name"),
    ('', "no runs"),
    ('[[runs]]\nname = "a"\nsett = []\n', "keys must be"),
])
def test_bad_sweep_files(tmp_path, body, match):
    with pytest.raises(casemod.CaseError, match=match):
        sweep.load(write_sweep(tmp_path, body))


def test_every_run_is_checked_before_any_starts(tmp_path):
    """An unknown key or an unstable step in one run stops the sweep before anything runs,
    naming the run and the key."""
    p = write_sweep(tmp_path, '[[runs]]\nname = "ok"\n[[runs]]\nname = "bad"\nset = ["time.step=1.0"]\n')
    with pytest.raises(casemod.CaseError, match=r"run 'bad'.*'step'.*critical"):
        sweep.run(p, results=tmp_path / "res")
    assert not (tmp_path / "res" / "s" / "ok").exists()
    p = write_sweep(tmp_path, '[[runs]]\nname = "bad"\nset = ["contact.kk=1"]\n')
    with pytest.raises(casemod.CaseError, match="kk"):
        sweep.run(p, results=tmp_path / "res")


@requires_yade
@pytest.mark.yade
def test_local_sweep_resumes_and_survives_a_failure(tmp_path, monkeypatch, capsys):
    p = write_sweep(tmp_path, '[grid]\n"contact.mu" = [0.3, 0.6]\n')
    res = sweep.run(p, workers=2, results=tmp_path / "res", heartbeat_s=1.0)
    assert res["failed"] == []
    root = Path(res["root"])
    for n in ("mu_0.3", "mu_0.6"):
        s = json.loads((root / n / "summary.json").read_text())
        assert s["inputs"]["materials"]["stone"]["mu"] == float(n.split("_")[1])
    status = json.loads((root / "sweep.json").read_text())
    assert {r["status"] for r in status["runs"]} == {"done"}
    # the results table: one row per run, read through analyses.common.outcome
    import csv
    from drystone.analyses.common import outcome
    rows = list(csv.DictReader((root / "runs.csv").open()))
    assert [r["run"] for r in rows] == ["mu_0.3", "mu_0.6"]
    assert [r["overrides"] for r in rows] == ["contact.mu=0.3", "contact.mu=0.6"]
    for r in rows:
        o = outcome(root / r["run"])
        assert r["status"] == "done" and r["collapsed"] == "no" and r["collapsed_stones"] == ""
        assert float(r["largest_residual_mm"]) == pytest.approx(1e3 * o["largest_residual_m"], rel=1e-3)
        assert r["onset_deg"] == ""  # no tilt stage
    printed = capsys.readouterr().out
    assert "runs.csv" in printed and "residual mm" in printed and "mu_0.6" in printed.split("results (")[-1]
    # second call: nothing to run; the summaries are rebuilt with the current post-processing
    stale = json.loads((root / "mu_0.3" / "summary.json").read_text())
    stale["blocks"] = "stale"
    (root / "mu_0.3" / "summary.json").write_text(json.dumps(stale))
    res = sweep.run(p, workers=2, results=tmp_path / "res")
    assert {r["status"] for r in res["runs"].values()} == {"skipped (finished earlier)"}
    assert json.loads((root / "mu_0.3" / "summary.json").read_text())["blocks"] != "stale"
    # an interrupted sweep (one run lost its summary) runs only what is missing
    (root / "mu_0.6" / "summary.json").unlink()
    res = sweep.run(p, workers=2, results=tmp_path / "res")
    assert res["runs"]["mu_0.6"]["status"] == "done"
    assert res["runs"]["mu_0.3"]["status"].startswith("skipped")
    # a changed input with the same overrides (here the base case's cube) is run again
    changed = json.loads(json.dumps(BASE))
    changed["case"]["geometry"]["boxes"][0]["size"] = [0.2, 0.2, 0.25]
    (tmp_path / "cube.toml").write_text(runner.to_toml(changed))
    res = sweep.run(p, workers=2, results=tmp_path / "res")
    assert {r["status"] for r in res["runs"].values()} == {"done"}
    # a run that fails while running is reported with its log and the others still run
    p2 = write_sweep(tmp_path, '[[runs]]\nname = "good"\n[[runs]]\nname = "broken"\nset = ["time.step=1.0"]\n')
    monkeypatch.setattr(sweep, "validate", lambda jobs: {j.name: None for j in jobs})  # let it reach the runner
    res = sweep.run(p2, workers=2, results=tmp_path / "res2")
    assert res["failed"] == ["broken"]
    assert res["runs"]["good"]["status"] == "done"
    assert "critical" in (Path(res["root"]) / "broken" / "FAILED.txt").read_text()


@requires_yade
@pytest.mark.yade
def test_dask_local_cluster_runs_and_resumes(tmp_path):
    """The distributed path: a Dask LocalCluster of two worker processes."""
    pytest.importorskip("distributed")
    p = write_sweep(tmp_path, '[grid]\n"contact.mu" = [0.3, 0.6]\n')
    res = sweep.run(p, workers=2, backend="dask", dask_address="local", results=tmp_path / "res")
    assert res["failed"] == [] and {r["status"] for r in res["runs"].values()} == {"done"}
    (Path(res["root"]) / "mu_0.3" / "summary.json").unlink()
    res = sweep.run(p, workers=2, backend="dask", dask_address="local", results=tmp_path / "res")
    assert res["runs"]["mu_0.3"]["status"] == "done" and res["runs"]["mu_0.6"]["status"].startswith("skipped")
