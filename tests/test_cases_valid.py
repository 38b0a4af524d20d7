"""Every case file shipped in cases/ validates and resolves (geometry, time step, stages)
without starting YADE."""
import pytest

from drystone import case as casemod
from drystone import paths, runner

CASES = sorted(paths.CASES.rglob("*.toml"))


@pytest.mark.parametrize("path", CASES, ids=[str(p.relative_to(paths.CASES)) for p in CASES])
def test_case_resolves(path, tmp_path):
    c = casemod.load(path)
    spec = runner.resolve(c, str(path), tmp_path)
    assert 0 < spec["dt"] < spec["dt_critical"]
    assert spec["stages"][-1]["end"] > 0
    assert (tmp_path / "geometry.json").is_file()
