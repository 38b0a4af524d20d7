"""Packaging: pyproject.toml declares every third-party module the package imports, the
licence file it names exists, ``--version`` answers, and ``make help`` lists every target."""
from __future__ import annotations

import ast
import importlib.metadata as md
import re
import subprocess
import sys
import tomllib

import drystone
from drystone import paths

PYPROJECT = tomllib.loads((paths.ROOT / "pyproject.toml").read_text())
#: imported but with no PyPI distribution: YADE is Debian's package `yade` (make setup installs it)
NOT_ON_PYPI = {"yade"}


def _dist_name(requirement: str) -> str:
    return re.split(r"[\s<>=!~;\[]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def _imports() -> dict[str, str]:
    """Top-level third-party modules imported anywhere in drystone/ -> the first file importing it."""
    found = {}
    for path in sorted(paths.PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else [])
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top != "drystone":
                    found.setdefault(top, str(path.relative_to(paths.ROOT)))
    return found


def test_every_import_is_declared():
    declared = {_dist_name(r) for r in PYPROJECT["project"]["dependencies"]}
    for extra in PYPROJECT["project"].get("optional-dependencies", {}).values():
        declared |= {_dist_name(r) for r in extra}
    dists = md.packages_distributions()
    missing = []
    for module, where in _imports().items():
        if module in NOT_ON_PYPI:
            continue
        names = {d.lower().replace("_", "-") for d in dists.get(module, [module])}
        if not names & declared:
            missing.append(f"{module} ({where}; distribution {sorted(names)})")
    assert not missing, "imported but not declared in pyproject.toml: " + ", ".join(missing)


def test_the_licence_named_exists():
    lic = PYPROJECT["project"]["license"]
    text = (paths.ROOT / lic["file"]).read_text()
    assert text.startswith("MIT License") and "Permission is hereby granted" in text


def test_version():
    out = subprocess.run([sys.executable, "-m", "drystone", "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"drystone {drystone.__version__}" == f"drystone {PYPROJECT['project']['version']}"


def test_make_help_lists_every_target():
    makefile = (paths.ROOT / "Makefile").read_text()
    phony = set(" ".join(re.findall(r"^\.PHONY:((?:.*\\\n)*.*)$", makefile, re.M)).replace("\\", " ").split())
    rules = set(re.findall(r"^([a-z][\w-]*):", makefile, re.M))
    help_text = subprocess.run(["make", "-s", "help"], cwd=paths.ROOT, capture_output=True, text=True, check=True).stdout
    listed = set(re.findall(r"\bmake ([a-z][\w-]*)", help_text)) | set(re.findall(r"\| ([a-z][\w-]*)", help_text))
    internal = {"help", "system-deps"}
    assert rules - phony == set(), f"targets not in .PHONY: {sorted(rules - phony)}"
    assert rules - internal - listed == set(), f"targets missing from make help: {sorted(rules - internal - listed)}"
