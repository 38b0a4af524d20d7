"""Every case file shipped in cases/ validates and resolves (geometry, time step, stages)
without starting YADE; so does every run of every sweep in cases/sweeps/."""
from pathlib import Path

import pytest

from drystone.model import case as casemod
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


def test_shipped_names_do_not_clash(tmp_path):
    """Issue 23: a case and a sweep of the same name wrote one folder (running the case after
    the sweep deleted the sweep's runs). Every results folder the shipped files write,
    results/<case name>/, results/<sweep>/ and each sweep run's own folder, is distinct,
    and none lies inside another that is not its sweep's."""
    owners = {}  # folder -> what writes it
    for path in CASES:
        owners.setdefault(casemod.load(path)["case"]["name"], []).append(f"case {path.name}")
    for path in SWEEPS:
        name, jobs = sweep.load(path, results=tmp_path)
        owners.setdefault(name, []).append(f"sweep {path.name}")
        for j in jobs:
            rel = str(Path(j.out_dir).relative_to(tmp_path))
            if not rel.startswith(f"{name}/"):  # an 'out' of its own, outside the sweep's folder
                owners.setdefault(rel, []).append(f"run {j.name} of {path.name}")
    clashes = {k: v for k, v in owners.items() if len(v) > 1}
    assert not clashes, clashes
    nested = [(a, b) for a in owners for b in owners if a != b and b.startswith(a + "/")]
    assert not nested, nested
