"""Issue 12 (reliability), case files: every bad input gives a CaseError naming the case
file and the key (or the override), never a traceback or a silent acceptance."""
import json

import numpy as np
import pytest

import tolerances as tol
from drystone.model import case as casemod
from drystone import paths, runner
from drystone.model import timestep
from drystone.motions import excitation, generators

BOX = '{generator = "boxes_on_platform", boxes = [{id = 1, center_xy = [0.0, 0.0], size = [0.2, 0.2, 0.2]}]}'
GOOD = f"""
[case]
name = "wall"
geometry = {BOX}
[[stages]]
type = "gravity"
duration = 1.0
[[stages]]
type = "rest"
duration = 1.0
"""
SINE = f"""
[case]
geometry = {BOX}
[[stages]]
type = "gravity"
duration = 1.0
[[stages]]
type = "excitation"
motion = "sine"
frequency_hz = 2.0
duration = 1.0
"""


def write(tmp_path, text, name="c.toml"):
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(text)
    return p


def refused(path, overrides=(), *fragments):
    """Load ``path`` with ``overrides``; assert a CaseError naming the file and every fragment."""
    with pytest.raises(casemod.CaseError) as err:
        casemod.load(path, list(overrides))
    msg = str(err.value)
    assert path.name in msg, msg
    for f in fragments:
        assert f in msg, msg
    return msg


# -- 1. time.safety in (0, 1] ---------------------------------------------------------
@pytest.mark.parametrize("value", ["3", "1000", "1.0001", "0", "-1", "true", '"half"'])
def test_safety_outside_0_1_refused(tmp_path, value):
    refused(write(tmp_path, GOOD), [f"time.safety={value}"], "[time]", "'safety'")


def test_safety_one_accepted(tmp_path):
    assert casemod.load(write(tmp_path, GOOD), ["time.safety=1"])["time"]["safety"] == 1.0


# -- 2. override paths ------------------------------------------------------------------
@pytest.mark.parametrize("override, why", [
    ("stages.5.x=1", "there are 2 stages (stages.0 .. stages.1; stages.0 is the first)"),
    ("stages.2.duration=1", "there are 2 stages"),
    ("stages.x.duration=1", "stages are addressed by index from 0"),
    ("stages.-1.duration=1", "stages are addressed by index from 0"),
    ("stages.1=3", "stages.1 is a table: set its keys"),
    ("stages=3", "stages is a section"),
    ("stages.1.duration.x=1", "stages.1.duration is 1.0, not a table"),
    ("case.name.foo=1", "case.name is 'wall', not a table"),
    ("time.step.x=1", "time.step is a float/str, not a table"),
    ("contact=5", "contact is a section"),
    ("case=5", "case is a section"),
    ("=1", "empty key"),
    ("a..b=1", "empty key"),
    ("time.=1", "empty key"),
    (".time.step=1", "empty key"),
])
def test_bad_override_path_named(tmp_path, override, why):
    refused(write(tmp_path, GOOD), [override], f"override {override!r}", why)


def test_override_without_equals(tmp_path):
    refused(write(tmp_path, GOOD), ["time.step"], "'time.step' is not of the form key=value")


def test_contact_replaced_by_scalar_when_present(tmp_path):
    p = write(tmp_path, GOOD + "\n[contact]\nmu = 0.6\n")
    refused(p, ["contact=5"], "override 'contact=5'", "contact is a section")


def test_stage_overrides_count_from_zero_and_good_paths_work(tmp_path):
    """stages.1 is the second stage (as the shipped sweeps use it); new tables are created."""
    c = casemod.load(write(tmp_path, GOOD), [
        "stages.1.duration=2.5", "stages.0.ramp=0.25", "materials.stone.mu=0.5", "contact.kn=1e8",
        f"case.geometry={BOX}", "stages.1={type = 'rest', duration = 3.0}"])
    assert c["stages"][0]["ramp"] == 0.25 and c["stages"][1]["duration"] == 3.0
    assert c["materials"] == {"stone": {"mu": 0.5}} and c["contact"]["kn"] == 1e8
    block = str(paths.CASES / "examples" / "one_block.json")
    c = casemod.load(write(tmp_path, GOOD), [f"case.geometry={block}"])  # a table replaced by a file
    assert c["case"]["geometry"] == block


# -- 3. validation gaps --------------------------------------------------------------------
@pytest.mark.parametrize("start, end", [(2.0, 1.0), (1.0, 1.0)])
def test_force_ending_before_it_starts(tmp_path, start, end):
    p = write(tmp_path, GOOD + f"[[forces]]\nblock = 1\nforce = [1.0, 0.0, 0.0]\nstart = {start}\nend = {end}\n")
    refused(p, [], "[[forces]] #1", f"'end' ({end} s) must be after 'start' ({start} s)")


@pytest.mark.parametrize("stage", ["to_deg = 200.0", "until_collapse = true\nmax_deg = 200.0",
                                   "until_collapse = true\nmax_deg = 90.5"])
def test_tilt_beyond_vertical(tmp_path, stage):
    p = write(tmp_path, GOOD + f'[[stages]]\ntype = "tilt"\nrate_deg_s = 1.0\n{stage}\n')
    key = stage.split("\n")[-1].split(" ")[0]
    refused(p, [], "[[stages]] #3", f"'{key}'", "exceeds 90 deg")


def test_tilt_to_90_accepted(tmp_path):
    p = write(tmp_path, GOOD + '[[stages]]\ntype = "tilt"\nrate_deg_s = 1.0\nto_deg = 90\n')
    assert casemod.load(p)["stages"][2]["to_deg"] == 90.0


@pytest.mark.parametrize("name", ["", " ", ".", "..", "../x", "a/../../b", "a/./b", "/tmp/x", "a//b", "a/",
                                  "a\\b", "..\\x", "C:\\x"])
def test_case_name_outside_results_refused(tmp_path, name):
    msg = refused(write(tmp_path, GOOD), [f"case.name={json.dumps(name)}"], "[case] 'name'", "results/<name>/")
    assert repr(name) in msg


@pytest.mark.parametrize("name", ["wall", "wall-1.5", "a..b", "_x", "A" * 100])
def test_plain_names_accepted(tmp_path, name):
    assert casemod.load(write(tmp_path, GOOD), [f"case.name={json.dumps(name)}"])["case"]["name"] == name


def test_only_sweeps_name_their_runs_sweep_slash_run(tmp_path):
    """Sweeps name their runs <sweep>/<run> (drystone/sweep.py); a user's name does not nest
    (a run named rx would replace results/rx/, deleting a run named rx/inner)."""
    p = write(tmp_path, GOOD)
    assert casemod.load(p, ["case.name=\"sweep/run_1\""], sweep_run=True)["case"]["name"] == "sweep/run_1"
    refused(p, ["case.name=\"rx/inner\""], "[case] 'name'", "no '/'")
    with pytest.raises(casemod.CaseError, match="one folder name"):
        casemod.load(p, ["case.name=\"a/b/c\""], sweep_run=True)


def _record_case(record):
    return SINE.replace('motion = "sine"\nfrequency_hz = 2.0', f'motion = "record"\nrecord = {record!r}')


def test_record_path_relative_to_the_case_file(tmp_path, monkeypatch):
    """As 'geometry': a record file is found beside the case file whatever the working folder."""
    rec = tmp_path / "cases" / "rec.txt"
    rec.parent.mkdir()
    rec.write_text("# dt = 0.01\n# units = m/s^2\n" + "\n".join(f"{np.sin(0.1 * k):.6f}" for k in range(201)) + "\n")
    p = write(tmp_path, _record_case("rec.txt"), "cases/c.toml")
    monkeypatch.chdir(tmp_path)  # where 'rec.txt' is not
    c = casemod.load(p)
    assert c["stages"][1]["record"] == str(rec.resolve())
    acc, dt, _ = excitation.for_stage(c["stages"][1])
    assert dt == 0.01 and len(acc) == 101  # trimmed to the stage's 1 s


def test_record_missing_file_named(tmp_path):
    refused(write(tmp_path, _record_case("nowhere.csv")), [], "[[stages]] #2", "'record' = 'nowhere.csv'",
            "neither a catalogue name", str(tmp_path / "nowhere.csv"))


def test_record_catalogue_name_kept(tmp_path):
    c = casemod.load(write(tmp_path, _record_case("kobe1995")))
    assert c["stages"][1]["record"] == "kobe1995"


@pytest.mark.parametrize("text, fragments", [
    (GOOD.replace("duration = 1.0", 'duration = "1"', 1), ["[[stages]] #1", "'duration' must be of type float",
                                                           "'1' (str)"]),
    (GOOD.replace("duration = 1.0", "duration = true", 1), ["[[stages]] #1", "'duration'", "True (bool)"]),
    (GOOD + "[time]\nstep = true\n", ["[time]", "'step'", "True (bool)"]),
    (GOOD + '[contact]\nmu = "0.5"\n', ["[contact]", "'mu' must be of type float"]),
    (GOOD + "[analysis]\ntilt_block = true\n", ["[analysis]", "'tilt_block' must be of type int"]),
    (GOOD + "[analysis]\ntilt_block = 1.5\n", ["[analysis]", "'tilt_block' must be of type int"]),
    (SINE + "seed = false\n", ["[[stages]] #2", "'seed' must be of type int"]),
    (GOOD + "[[forces]]\nblock = 1\nforce = [true, 0, 0]\n", ["[[forces]] #1", "'force' must be three finite"]),
    (GOOD + "[[forces]]\nblock = true\nforce = [1, 0, 0]\n", ["[[forces]] #1", "'block' must be of type int"]),
    (GOOD + '[output]\ncontacts = [{name = "a", blocks = ["1", "2"]}]\n', ["[output] contacts[0]", "integer"]),
    (GOOD + '[output]\ncontacts = [{name = "a", blocks = 12}]\n', ["[output] contacts[0]"]),
    ("materials = 5\n" + GOOD, ["[materials] must be tables"]),
    ("forces = 5\n" + GOOD, ["'forces' must be an array of tables"]),
    ("contact = 5\n" + GOOD, ["[contact]: must be a table"]),
    (GOOD + "[materials]\nstone = 5\n", ["[materials.stone]: must be a table"]),
])
def test_wrong_types_named(tmp_path, text, fragments):
    refused(write(tmp_path, text), [], *fragments)


def test_wrong_types_from_overrides(tmp_path):
    """--set values are TOML: a bare word is a string, true a bool; neither is a number."""
    p = write(tmp_path, GOOD)
    refused(p, ["stages.0.duration=abc"], "[[stages]] #1", "'duration'", "'abc' (str)")
    refused(p, ["stages.0.duration=true"], "[[stages]] #1", "'duration'", "True (bool)")
    refused(p, ["physics.gravity=false"], "[physics]", "'gravity'", "False (bool)")


# -- 4. motions too fast or too long -----------------------------------------------------
def test_sine_too_fast_named(tmp_path):
    """A 1e8 Hz sine: refused before its samples are made (not a MemoryError), first as
    above the simulation step's Nyquist frequency (runner.resolve), and by the motion
    generator as too many samples (64 per period) if called directly."""
    p = write(tmp_path, SINE.replace("frequency_hz = 2.0", "frequency_hz = 1e8"))
    with pytest.raises(casemod.CaseError) as err:
        runner.resolve(casemod.load(p), str(p), tmp_path)
    msg = str(err.value)
    for f in ("c.toml", "[[stages]] #2", "1e+08 Hz", "Nyquist frequency"):
        assert f in msg, msg
    assert not list(tmp_path.glob("excitation_*.npy"))
    with pytest.raises(ValueError, match=r"6.4e\+09 samples, more than 1e\+07"):
        generators.sine(1e8, duration=1.0)


def test_sine_at_or_above_nyquist_refused():
    with pytest.raises(ValueError, match=r"frequency_hz = 150 Hz .* Nyquist frequency 100 Hz .* dt = 0.005 s"):
        generators.sine(150.0, duration=1.0, dt=0.005)
    with pytest.raises(ValueError, match=r"frequency_hz = 100 Hz is at or above the Nyquist frequency 100 Hz"):
        generators.sine(100.0, duration=1.0, dt=0.005)
    assert generators.sine(99.0, duration=1.0, dt=0.005).n == 201


def test_long_white_noise_refused_before_allocating(tmp_path):
    with pytest.raises(ValueError, match=r"duration = 1e\+06 s at rate_hz = 1000 Hz would need 1e\+09 samples"):
        generators.white_noise(duration=1e6)
    p = write(tmp_path, SINE.replace('motion = "sine"\nfrequency_hz = 2.0', 'motion = "white_noise"')
              .replace("duration = 1.0\n", "duration = 1e6\n").replace("duration = 1e6\n", "duration = 1.0\n", 1))
    with pytest.raises(casemod.CaseError, match=r"c.toml: \[\[stages\]\] #2 \(white_noise\): .*1e\+09 samples"):
        runner.resolve(casemod.load(p), str(p), tmp_path)


# -- 5. step count --------------------------------------------------------------------
DETAIL = {"block": 7, "mass_kg": 9.2e-11, "stiffness_N_per_m": 3.2e7, "damping": 0.8}


def test_step_count_check():
    assert timestep.step_count_check(1e-5, 10.0, "c.toml") == pytest.approx(1e6)
    assert timestep.step_count_check(1e-6, 50.0, "c.toml") == pytest.approx(5e7)  # the bound itself passes
    with pytest.raises(casemod.CaseError) as err:
        timestep.step_count_check(1e-9, 1.0, "c.toml", DETAIL)
    msg = str(err.value)
    for f in ("c.toml", "1e-09 s", "1e+09 steps", "more than 5e+07", "block 7", "mass 9.2e-11 kg", "3.2e+07 N/m"):
        assert f in msg, msg
    for dt in (0.0, -1e-5, float("nan"), float("inf")):
        with pytest.raises(casemod.CaseError, match="inf steps"):
            timestep.step_count_check(dt, 1.0, "c.toml")


def _cube(height, material="stone"):
    v = [[x, y, z] for x in (-0.1, 0.1) for y in (-0.1, 0.1) for z in (0.0, height)]
    return [{"id": 1, "role": "free", "material": material, "vertices": v}]


def test_sliver_block_gives_absurd_step_count():
    """A 0.2 x 0.2 x 1e-12 m sliver: m = 9.2e-11 kg, k = 4 K_n A = 3.2e7 N/m, dt_crit = 1.63e-9 s
    (damping 0.8); at safety 0.5, 0.5 s simulated is 6.14e8 steps: refused, naming the block."""
    stone = {"stone": {"density": 2300.0, "kn": 2e8, "damping": 0.8}}
    dt, detail = timestep.critical_step(_cube(1e-12), stone)
    assert dt == pytest.approx(1.63e-9, rel=tol.QUOTED_3_DIGITS_REL) and detail["block"] == 1
    with pytest.raises(casemod.CaseError, match=r"6.14e\+08 steps.*block 1 \(mass 9.2e-11 kg"):
        timestep.step_count_check(0.5 * dt, 0.5, "c.toml", detail)
    dt, detail = timestep.critical_step(_cube(0.2), stone)  # the same block 0.2 m high: fine
    assert timestep.step_count_check(0.5 * dt, 10.0, "c.toml", detail) < 1e6


@pytest.mark.parametrize("material", [{"density": 1e-300, "kn": 2e8}, {"density": 2300.0, "kn": 1e300}])
def test_absurd_material_gives_absurd_step_count(material):
    with np.errstate(over="ignore"):
        dt, detail = timestep.critical_step(_cube(0.2), {"stone": dict(material, damping=0.8)})
    with pytest.raises(casemod.CaseError, match="more than 5e\\+07"):
        timestep.step_count_check(dt, 1.0, "c.toml", detail)
