"""The run specification: typed and frozen, versioned, one upgrade for old spec.json
(drystone/model/spec.py; issue 13, item 3)."""
from __future__ import annotations

import dataclasses
import json

import pytest

from drystone.model import case as casemod
from drystone import paths, runner
from drystone.model.loading import LoadProgramme
from drystone.model.spec import (SPEC_VERSION, Spec, SpecError, StageSpec, load_spec, spec_dict, stage_type, upgrade,
                           upgrade_stage)

#: every stage type, an applied force and a recorded contact on the one-block example
PIN_CASE = {
    "case": {"geometry": str(paths.CASES / "examples" / "one_block.json"), "name": "pin"},
    "forces": [{"block": 1, "force": [1.0, 0.0, 0.0], "start": 0.1}],
    "output": {"contacts": [{"name": "c", "blocks": [0, 1]}]},
    "stages": [{"type": "gravity", "duration": 0.2, "ramp": 0.1},
               {"type": "settlement", "duration": 0.1, "block": 0, "displacement": 0.001},
               {"type": "excitation", "motion": "sine", "frequency_hz": 2.0, "duration": 0.3, "direction": "x",
                "start": "displacement"},
               {"type": "excitation", "motion": "white_noise", "duration": 0.2, "pga_g": 0.1, "seed": 3},
               {"type": "tilt", "rate_deg_s": 10.0, "to_deg": 2.0, "towards": "-x"},
               {"type": "rest", "duration": 0.1},
               {"type": "rest", "duration": 0.2, "until_kinetic_below_per_weight": 1e-7, "settle_window": 0.05}]}
#: Pins backward compatibility of finished runs: sweeps recognise a finished run by
#: comparing this hash of its spec.json with that of the case resolved now, so the
#: fingerprint of unchanged physics must never change (this value was computed with the
#: version-1 code, whose stages said "kind"). A change here re-runs every finished run.
PIN_FINGERPRINT = "12bd351f12ecb4ea8f2294644f43e02e956370a1ff969ecc5d11df4ce6a38c91"


def _spec(tmp_path) -> Spec:
    return runner.resolve(casemod.validate(PIN_CASE, "pin.toml", tmp_path), "pin.toml", tmp_path)


def _as_version_1(d: dict) -> dict:
    """A spec dict as version 1 wrote it: stages with "kind", version 1."""
    old = dict(d, version=1)
    old["stages"] = [{("kind" if k == "type" else k): v for k, v in st.items()} for st in d["stages"]]
    return old


def test_fingerprint_is_pinned_for_every_version(tmp_path):
    spec = _spec(tmp_path)
    assert runner.fingerprint(spec) == PIN_FINGERPRINT
    d = spec.to_dict()
    assert runner.fingerprint(d) == PIN_FINGERPRINT
    assert runner.fingerprint(json.loads(json.dumps(d))) == PIN_FINGERPRINT  # as spec.json
    v1 = _as_version_1(json.loads(json.dumps(d)))
    assert runner.fingerprint(v1) == PIN_FINGERPRINT
    no_header = {k: v for k, v in v1.items() if k not in ("format", "version")}  # the oldest spec.json
    assert runner.fingerprint(no_header) == PIN_FINGERPRINT


def test_spec_json_is_version_2_with_type(tmp_path):
    d = json.loads(json.dumps(_spec(tmp_path).to_dict()))
    assert (d["format"], d["version"]) == ("drystone-spec", SPEC_VERSION) and SPEC_VERSION == 4
    assert [st["type"] for st in d["stages"]] == [s["type"] for s in PIN_CASE["stages"]]
    assert all(list(st) == ["type", "start", "end", "params"] for st in d["stages"])
    assert list(d)[:3] == ["format", "version", "name"] and "provenance" not in d


def test_upgrade_renames_kind_and_leaves_its_input(tmp_path):
    new = json.loads(json.dumps(_spec(tmp_path).to_dict()))
    old = _as_version_1(new)
    before = json.dumps(old)
    assert upgrade(old) == new
    assert json.dumps(old) == before  # the input is not changed
    assert upgrade(new) == new
    assert upgrade_stage({"kind": "tilt", "params": {}}) == {"type": "tilt", "params": {}}  # summary inputs
    assert stage_type({"kind": "rest"}) == stage_type({"type": "rest"}) == "rest"
    with pytest.raises(SpecError, match=f"unsupported spec version {SPEC_VERSION + 1}"):
        upgrade(dict(new, version=SPEC_VERSION + 1))
    assert upgrade(dict(new, version=2)) == new  # version 3 only adds a block's optional 'parts'
    with pytest.raises(SpecError, match="not a run specification"):
        upgrade(dict(new, format="drystone.blocks"))


def test_spec_is_frozen(tmp_path):
    spec = _spec(tmp_path)
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.dt = 1.0
    with pytest.raises(TypeError):
        spec["dt"] = 1.0
    with pytest.raises(TypeError):
        spec.stages[0].params["ramp"] = 0.0
    with pytest.raises(TypeError):
        spec.materials["stone"] = {}
    with pytest.raises(AttributeError):
        spec.blocks.append({})  # a tuple
    # mapping access gives plain copies: changing them leaves the spec as it was
    d = spec["stages"]
    d[0]["params"]["ramp"] = 99.0
    assert spec.stages[0].params["ramp"] == 0.1 == spec["stages"][0]["params"]["ramp"]


def test_mapping_access_reads_like_the_json(tmp_path):
    spec = _spec(tmp_path)
    d = spec.to_dict()
    assert dict(spec) == d and list(spec) == list(d)
    assert spec["format"] == "drystone-spec" and spec["version"] == SPEC_VERSION
    assert spec["dt"] == spec.dt and "dt" in spec
    assert "provenance" not in spec and spec.get("provenance", "none") == "none"
    assert isinstance(spec.stages[0], StageSpec) and spec.stages[0].type == "gravity"
    assert spec["stages"][4]["params"]["towards"] == [-1.0, 0.0, 0.0]  # JSON lists, not tuples
    with pytest.raises(KeyError):
        spec["kind"]


def test_replace_is_the_one_way_to_change_a_spec(tmp_path):
    """The runner sets where the run will live and its provenance this way."""
    spec = _spec(tmp_path)
    moved = spec.replace(out_dir="/elsewhere", provenance={"overrides": []})
    assert moved.out_dir == "/elsewhere" and moved["provenance"] == {"overrides": []}
    assert spec.out_dir == str(tmp_path) and spec.provenance is None
    assert list(moved)[-1] == "provenance"


def test_load_spec_round_trip(tmp_path):
    spec = _spec(tmp_path)
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(spec.to_dict(), indent=1))
    assert load_spec(path) == spec
    assert load_spec(spec) is spec
    v1 = _as_version_1(json.loads(path.read_text()))
    assert load_spec(v1) == spec and spec_dict(v1) == spec.to_dict()
    with pytest.raises(SpecError, match=r"missing \['dt'\]"):
        load_spec({k: v for k, v in v1.items() if k != "dt"})
    with pytest.raises(SpecError, match=r"unknown \['extra'\]"):
        load_spec(dict(v1, extra=1))


def test_load_programme_reads_every_version(tmp_path):
    spec = _spec(tmp_path)
    v1 = _as_version_1(json.loads(json.dumps(spec.to_dict())))
    for source in (spec, spec.to_dict(), v1):
        prog = LoadProgramme.from_spec(source, tmp_path)
        assert [s.type for s in prog.stages] == [s["type"] for s in PIN_CASE["stages"]]
        assert prog.moving_blocks() == [0]
        assert prog.tilt_deg(10.0) == pytest.approx(2.0)
        assert len(prog.stages[2].params["acc"]) > 1  # the samples, from the run folder
