"""Stages may carry a name; overrides address them as stages.NAME.KEY (issue 13)."""
from __future__ import annotations

import pytest

from drystone.model import case as casemod

CASE = """
[case]
geometry = {generator = "boxes_on_platform", boxes = [{id = 1, center_xy = [0.0, 0.0], size = [0.2, 0.2, 0.2]}]}

[[stages]]
type = "gravity"
name = "settle"
duration = 1.0

[[stages]]
type = "excitation"
name = "shake"
motion = "sine"
frequency_hz = 2.0
duration = 1.0
"""


def _write(tmp_path, text=CASE):
    p = tmp_path / "c.toml"
    p.write_text(text)
    return p


def test_a_named_stage_is_addressed_by_name_or_index(tmp_path):
    p = _write(tmp_path)
    by_name = casemod.load(p, ["stages.shake.frequency_hz=3.5", "stages.settle.duration=2.0"])
    by_index = casemod.load(p, ["stages.1.frequency_hz=3.5", "stages.0.duration=2.0"])
    assert by_name["stages"][1]["frequency_hz"] == 3.5 == by_index["stages"][1]["frequency_hz"]
    assert by_name["stages"][0]["duration"] == 2.0 == by_index["stages"][0]["duration"]
    assert by_name["stages"][1]["name"] == "shake"


def test_an_unknown_stage_name_lists_the_names(tmp_path):
    with pytest.raises(casemod.CaseError, match=r"stages\.shak.*or by name \(settle, shake\)"):
        casemod.load(_write(tmp_path), ["stages.shak.frequency_hz=3.5"])


@pytest.mark.parametrize("bad, why", [('"3"', "not a number"), ('"a.b"', "without '.'"), ('"settle"', "already")])
def test_bad_stage_names_are_refused(tmp_path, bad, why):
    text = CASE.replace('name = "shake"', f"name = {bad}")
    with pytest.raises(casemod.CaseError, match=why):
        casemod.load(_write(tmp_path, text))
