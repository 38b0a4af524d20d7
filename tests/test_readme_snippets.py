"""The documentation's snippets do not go stale (README.md and docs/*.md; blocks read by
tests/docblocks.py). Without running anything:

* every TOML block parses, and a complete case in one (with [[stages]] and a generated
  geometry that reads no file) validates; every JSON block parses;
* every python block (runnable or not) parses, and each module it imports exists and has
  the names it imports; so does every inline ``from X import Y`` of the text (the old
  ``from geometry import irregular_wall`` did not exist, and a TOML example split an inline
  table over lines, which TOML does not allow);
* every ``python -m MODULE`` names a module, every `` `make TARGET` `` a Makefile target;
* every relative link names a file (and a heading of it, for ``#anchor``);
* no page refers the reader to internal issue numbers they cannot see.

The runnable blocks themselves run in tests/test_docs_runnable.py.
"""
from __future__ import annotations

import ast
import importlib
import importlib.util
import json
import re
import tomllib

import pytest

from docblocks import ROOT, all_blocks, documents
from drystone.model import case as casemod

BLOCKS = all_blocks()
TEXTS = {doc: doc.read_text() for doc in documents()}
#: pages and targets other parts of the project add (linked before they exist): checked once they do
PENDING_PAGES = {"docs/energy.md", "docs/reports.md", "docs/damping-and-impacts.md", "docs/paraview.md"}


def _rel(doc):
    return str(doc.relative_to(ROOT))


def _blocks(lang):
    return [pytest.param(b, id=b.where) for b in BLOCKS if b.lang == lang]


@pytest.mark.parametrize("block", _blocks("toml"))
def test_toml_blocks_parse(block, tmp_path):
    data = tomllib.loads(block.code)
    geo = data.get("case", {}).get("geometry")
    if "stages" in data and isinstance(geo, dict) and not {"file", "files", "folder"} & set(geo):
        casemod.validate(data, block.where, tmp_path)


@pytest.mark.parametrize("block", _blocks("json"))
def test_json_blocks_parse(block):
    json.loads(block.code)


def _imports_exist(module: str, names: list[str], where: str) -> None:
    mod = importlib.import_module(module)
    for name in names:
        assert hasattr(mod, name) or importlib.util.find_spec(f"{module}.{name}"), f"{where}: {module}.{name}"


@pytest.mark.parametrize("block", _blocks("python"))
def test_python_blocks_import_what_exists(block):
    tree = ast.parse(block.code, block.where)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                importlib.import_module(alias.name)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0 and node.module, f"{block.where}: relative import"
            _imports_exist(node.module, [a.name for a in node.names], block.where)


INLINE_IMPORTS = sorted({(m, n, _rel(doc)) for doc, text in TEXTS.items()
                         for m, n in re.findall(r"\bfrom ([a-z_][\w.]*) import ([\w ,]+?)(?:;|\"|\n|`|$|\))", text)})


@pytest.mark.parametrize("module, names, doc", INLINE_IMPORTS, ids=[f"{d}:{m}" for m, _, d in INLINE_IMPORTS])
def test_inline_imports_exist(module, names, doc):
    _imports_exist(module, [n.strip().split(" as ")[0].strip() for n in names.split(",") if n.strip()], doc)


MODULES = sorted({(m, _rel(doc)) for doc, text in TEXTS.items() for m in re.findall(r"python3? -m ([a-z_][a-z0-9_]*(?:\.[a-z_][a-z0-9_]*)*)(?![\w.])", text)})  # NAME: a placeholder


@pytest.mark.parametrize("module, doc", MODULES, ids=[f"{d}:{m}" for m, d in MODULES])
def test_python_m_modules_exist(module, doc):
    if module in ("pip", "venv", "pytest"):
        return
    assert importlib.util.find_spec(module), f"{doc}: python -m {module}"


def test_make_targets_exist():
    rules = set(re.findall(r"^([a-z][\w-]*):", (ROOT / "Makefile").read_text(), re.M))
    named = {(t, _rel(doc)) for doc, text in TEXTS.items() for t in re.findall(r"`make ([a-z][\w-]*)", text)}
    named |= {(line.split()[1], b.where) for b in BLOCKS if b.lang == "sh"
              for line in b.code.splitlines() if line.startswith("make ")}
    missing = sorted((t, where) for t, where in named if t not in rules)
    assert not missing, f"make targets the documentation names but the Makefile lacks: {missing}"


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def _anchors(path) -> set[str]:
    text = path.read_text()
    text = re.sub(r"^```.*?^```", "", text, flags=re.M | re.S)
    return {_slug(h) for h in re.findall(r"^#{1,6} (.+)$", text, re.M)}


LINKS = sorted({(_rel(doc), target, anchor) for doc, text in TEXTS.items()
                for target, anchor in re.findall(r"\]\(([^)#\s]*)(#[^)\s]*)?\)", text)
                if not re.match(r"[a-z]+:", target)})


@pytest.mark.parametrize("doc, target, anchor", LINKS, ids=[f"{d}->{t}{a}" for d, t, a in LINKS])
def test_relative_links_resolve(doc, target, anchor):
    path = (ROOT / doc).parent / target if target else ROOT / doc
    rel = str(path.resolve().relative_to(ROOT)) if path.resolve().is_relative_to(ROOT) else str(path)
    if not path.exists() and rel in PENDING_PAGES:
        pytest.skip(f"{rel} is not written yet")
    assert path.exists(), f"{doc}: link to {target} (no such file)"
    if anchor and path.is_file() and path.suffix == ".md":
        assert anchor[1:] in _anchors(path), f"{doc}: link to {target}{anchor}: no such heading in {rel}"


@pytest.mark.parametrize("doc", list(TEXTS), ids=[_rel(d) for d in TEXTS])
def test_no_internal_issue_references(doc):
    hits = re.findall(r".{0,40}(?:\bissues? \d+|the issue's|\(issue\b|issue-\d+).{0,40}", TEXTS[doc], re.I)
    assert not hits, f"{_rel(doc)}: internal issue references: {hits}"


def test_there_is_something_to_check():
    assert len(_blocks("toml")) >= 3 and len(_blocks("python")) >= 2
    assert any("from drystone.geometry import" in b.code for b in BLOCKS if b.lang == "python")
    assert len(LINKS) >= 20 and len(MODULES) >= 5
