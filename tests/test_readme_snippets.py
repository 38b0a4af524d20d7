"""README's snippets do not go stale: every TOML block parses (and a complete case in one,
with [[stages]], validates), and every `from drystone... import ...` in the README names
modules and attributes that exist (the old `from geometry import irregular_wall` did not,
and a TOML example split an inline table over lines, which TOML does not allow)."""
from __future__ import annotations

import importlib
import re
import tomllib

import pytest

from drystone import paths
from drystone.model import case as casemod

README = (paths.ROOT / "README.md").read_text()
TOML_BLOCKS = re.findall(r"```toml\n(.*?)```", README, re.S)
IMPORTS = sorted(set(re.findall(r"\bfrom ([a-z_][\w.]*) import ([\w ,]+?)(?:;|\"|\n|`|$)", README)))


@pytest.mark.parametrize("block", TOML_BLOCKS, ids=[f"toml{k}" for k in range(len(TOML_BLOCKS))])
def test_toml_blocks_parse(block, tmp_path):
    data = tomllib.loads(block)
    if "stages" in data and isinstance(data.get("case", {}).get("geometry"), dict):
        casemod.validate(data, "README", tmp_path)


@pytest.mark.parametrize("module, names", IMPORTS, ids=[m for m, _ in IMPORTS])
def test_readme_imports_exist(module, names):
    mod = importlib.import_module(module)
    for item in names.split(","):
        name = item.strip().split(" as ")[0].strip()
        if name:
            assert hasattr(mod, name) or importlib.util.find_spec(f"{module}.{name}"), f"{module}.{name}"


def test_there_is_something_to_check():
    assert len(TOML_BLOCKS) >= 3 and any(m == "drystone.geometry" for m, _ in IMPORTS)
