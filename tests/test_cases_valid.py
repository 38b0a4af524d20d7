"""Every case file shipped in cases/ validates and resolves (geometry, time step, stages)
without starting YADE; so does every run of every sweep in cases/sweeps/."""
import pytest

from drystone import case as casemod
from drystone import paths, runner, sweep

SWEEPS = sorted((paths.CASES / "sweeps").glob("*.toml"))
CASES = sorted(p for p in paths.CASES.rglob("*.toml") if p not in SWEEPS)


@pytest.mark.parametrize("path", CASES, ids=[str(p.relative_to(paths.CASES)) for p in CASES])
def test_case_resolves(path, tmp_path):
    c = casemod.load(path)
    spec = runner.resolve(c, str(path), tmp_path)
    assert 0 < spec["dt"] < spec["dt_critical"]
    assert spec["stages"][-1]["end"] > 0
    assert (tmp_path / "geometry.json").is_file()


@pytest.mark.parametrize("path", SWEEPS, ids=[p.name for p in SWEEPS])
def test_sweep_resolves(path, tmp_path):
    name, jobs = sweep.load(path, results=tmp_path)
    assert name == path.stem and jobs
    sweep.validate(jobs)
