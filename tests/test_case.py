"""Case files: every bad input fails before any simulation, naming the key."""
import pytest

import tolerances as tol
from drystone.model import case as casemod
from drystone import runner

GOOD = """
[case]
geometry = {generator = "boxes_on_platform", boxes = [{id = 1, center_xy = [0.0, 0.0], size = [0.2, 0.2, 0.2]}]}
[[stages]]
type = "gravity"
duration = 1.0
"""


def write(tmp_path, text, name="c.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_defaults_filled(tmp_path):
    c = casemod.load(write(tmp_path, GOOD))
    assert c["case"]["name"] == "c"
    assert c["contact"]["law"] == "penalty_coulomb"
    assert c["stages"][0]["ramp"] == 0.5
    assert c["time"]["step"] == "auto"


@pytest.mark.parametrize("text, message", [
    (GOOD + "\n[time]\nstepp = 1e-4\n", "[time]: unknown key(s) ['stepp']"),
    (GOOD + "\n[solver]\nx = 1\n", "unknown section(s) ['solver']"),
    (GOOD.replace('type = "gravity"', 'type = "shake"'), "unknown stage type 'shake'"),
    (GOOD + "\n[contact]\nkn = -2e8\n", "[contact]: 'kn' must be > 0"),
    (GOOD + "\n[contact]\nkt = 0.0\n", "[contact]: 'kt' must be > 0"),
    (GOOD + "\n[contact]\nlaw = \"magic\"\n", "'law' must be one of"),
    ('[case]\ngeometry = "nowhere.json"\n[[stages]]\ntype = "gravity"\nduration = 1.0\n', "nowhere.json not found"),
    ("[case]\nname = 'x'\n", "missing required key 'geometry'"),
])
def test_bad_case_names_the_key(tmp_path, text, message):
    with pytest.raises(casemod.CaseError) as err:
        casemod.load(write(tmp_path, text))
    assert message in str(err.value)
    assert "c.toml" in str(err.value)


def test_missing_case_file(tmp_path):
    with pytest.raises(casemod.CaseError, match="case file not found"):
        casemod.load(tmp_path / "none.toml")


def test_unstable_step_refused_before_simulation(tmp_path):
    """An explicit step above the critical one is refused, and no result is left."""
    p = write(tmp_path, GOOD + "\n[time]\nstep = 0.01\n")
    out = tmp_path / "out"
    with pytest.raises(casemod.CaseError) as err:
        runner.run(p, out_dir=out, quiet=True)
    assert "[time] 'step' = 0.01 s exceeds the critical step" in str(err.value)
    assert not (out / "summary.json").exists() and not (out / "histories.npz").exists()


def test_override_unknown_material(tmp_path):
    p = write(tmp_path, GOOD)
    with pytest.raises(casemod.CaseError, match=r"\[materials.granite\]"):
        runner.run(p, ["materials.granite.mu=0.5"], out_dir=tmp_path / "o", quiet=True)


def test_overrides_apply(tmp_path):
    c = casemod.load(write(tmp_path, GOOD), ["contact.law=stock_volumetric", "time.step=1e-4"])
    assert c["contact"]["law"] == "stock_volumetric" and c["time"]["step"] == 1e-4


def test_auto_step_is_safety_times_critical(tmp_path):
    """Critical step of a 0.2 m cube on its face: (2/omega)(sqrt(1+xi^2)-xi),
    omega^2 = 4 K_n A / m (drystone/model/timestep.py)."""
    import math
    from drystone.model import timestep
    c = casemod.load(write(tmp_path, GOOD))
    spec = runner.resolve(c, "t", tmp_path)
    m = 2300 * 0.2 ** 3
    w = math.sqrt(4 * 2e8 * 0.04 / m)
    assert spec["dt_critical"] == pytest.approx(2 / w, rel=tol.NUMERICAL_REL)
    assert spec["dt"] == pytest.approx(0.5 * 2 / w, rel=tol.NUMERICAL_REL)
    del timestep


def test_readme_documents_every_key():
    """docs/case-keys.md's key table is generated from the declarations (python -m drystone keys --update-docs)."""
    from drystone import paths
    text = (paths.DOCS / "case-keys.md").read_text()
    assert casemod.readme_with_keys(text) == text


def test_stage_keys_live_with_the_stage_types(tmp_path):
    """One home for a stage's keys and checks: drystone/model/stages.py's REGISTRY (issue 13)."""
    import re

    from drystone.model.stages import REGISTRY

    assert not hasattr(casemod, "STAGES")
    text = GOOD.replace('type = "gravity"', 'type = "spin"')
    with pytest.raises(casemod.CaseError, match=re.escape(f"unknown stage type 'spin'; allowed: {sorted(REGISTRY)}")):
        casemod.load(write(tmp_path, text))
