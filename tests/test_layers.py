"""The package's layers depend one way (docs/maintainers-guide.md, Layout): geometry and motions -> core ->
yade_scripts -> postprocess -> studies, with runner, sweep, cli, bench and the analyses (free_decay among them) on top.
Checked on the import statements of every module (ast), wherever they are in the module."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import requires_yade
from drystone import paths
from drystone.layers import LAYERS, layer_of, readme_with_layout

def _layer(mod: str) -> int:
    """The rank of a module's layer (drystone/layers.py, the one list of them)."""
    try:
        return layer_of(mod).rank
    except KeyError as exc:
        raise AssertionError(str(exc)) from None


def _modules():
    for p in sorted(paths.PACKAGE.rglob("*.py")):
        rel = p.relative_to(paths.ROOT).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        yield ".".join(parts), p


def _imports(mod: str, path: Path):
    pkg = mod if path.name == "__init__.py" else mod.rsplit(".", 1)[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                base = ".".join(up + ([node.module] if node.module else []))
            for a in node.names:  # "from drystone import case" names a module
                full = f"{base}.{a.name}"
                yield full if _is_module(full) else base


def _is_module(name: str) -> bool:
    p = paths.ROOT.joinpath(*name.split("."))
    return p.with_suffix(".py").is_file() or (p / "__init__.py").is_file()


def _target(name: str) -> str | None:
    """The drystone module an import names (its longest existing prefix), or None."""
    if not name.startswith("drystone"):
        return None
    parts = name.split(".")
    while parts and not _is_module(".".join(parts)):
        parts.pop()
    return ".".join(parts) or None


def upward_imports(modules) -> list[str]:
    """The imports of the (module name, path) pairs that go up the layers, one line each."""
    bad = []
    for mod, path in modules:
        here = _layer(mod)
        for name in _imports(mod, path):
            t = _target(name)
            if t is None or t == mod or t.startswith(mod + "."):
                continue
            if _layer(t) > here:
                bad.append(f"{mod} (layer {here}) imports {t} (layer {_layer(t)})")
    return bad


def _imports_yade(mod: str, path: Path) -> bool:
    """Whether the module imports yade (``import yade``, ``import yade.x``, ``from yade
    import ...``), wherever in the module."""
    return any(name == "yade" or name.startswith("yade.") for name in _imports(mod, path))


def yade_importers(modules) -> list[str]:
    """The modules of the (module name, path) pairs outside drystone.yade_scripts that
    import yade."""
    return [mod for mod, path in modules if not mod.startswith("drystone.yade_scripts") and _imports_yade(mod, path)]


def test_every_import_goes_down_the_layers():
    bad = upward_imports(_modules())
    assert not bad, "\n".join(bad)


def test_the_layer_rule_catches_an_upward_import(tmp_path):
    """The check itself can fail: a geometry module importing postprocess (at the top, by
    a relative import and inside a function) or the runner is caught, each import once,
    and the same module importing only downwards passes."""
    assert _layer("drystone.geometry.blockfile") < _layer("drystone.runner")
    assert _target("drystone.runner.run") == "drystone.runner"
    up = tmp_path / "upward.py"
    up.write_text("import numpy as np\n"
                  "from drystone import paths\n"
                  "from drystone.postprocess import summary\n"
                  "from ..postprocess import vtk\n"
                  "def f():\n"
                  "    import drystone.runner\n"
                  "    return drystone.runner\n")
    bad = upward_imports([("drystone.geometry.upward", up)])
    assert bad == ["drystone.geometry.upward (layer 1) imports drystone.postprocess.summary (layer 4)",
                   "drystone.geometry.upward (layer 1) imports drystone.postprocess.vtk (layer 4)",
                   "drystone.geometry.upward (layer 1) imports drystone.runner (layer 5)"]
    down = tmp_path / "downward.py"
    down.write_text("from drystone import paths, units\nfrom . import blockfile\nimport drystone.motions.record\n")
    assert upward_imports([("drystone.geometry.downward", down)]) == []
    # the same upward imports are allowed to a module above them
    assert upward_imports([("drystone.studies.upward", up)]) == []


def test_only_the_yade_scripts_import_yade():
    """YADE is imported only inside YADE's interpreter, by drystone/yade_scripts: every
    other module imports without it (the package's pure parts run under plain Python)."""
    modules = list(_modules())
    assert yade_importers(modules) == []
    assert "drystone.yade_scripts.run_case" in [m for m, p in modules if _imports_yade(m, p)]  # the scan sees yade


def test_the_yade_rule_catches_a_yade_import(tmp_path):
    checks = {"import yade\n": True, "from yade import utils\n": True, "import yade.utils as u\n": True,
              "def f():\n    from yade import O\n": True, "import yadex\nfrom drystone import paths\n": False}
    for k, (text, caught) in enumerate(checks.items()):
        f = tmp_path / f"m{k}.py"
        f.write_text(text)
        assert yade_importers([("drystone.postprocess.m", f)]) == (["drystone.postprocess.m"] if caught else []), text
        assert yade_importers([("drystone.yade_scripts.m", f)]) == []


@requires_yade
def test_the_yade_driver_imports_without_running():
    """Importing run_case inside YADE defines Driver and runs nothing (main only as __main__)."""
    script = ("from drystone.yade_scripts import run_case\n"
              "print('DRIVER', callable(run_case.Driver), len(O.bodies))\n")
    r = subprocess.run([sys.executable, "/usr/bin/yade", "-n", "-x", "-c", script], capture_output=True, text=True,
                       timeout=120, cwd=paths.ROOT)
    if "DRIVER" not in r.stdout:  # older launchers have no -c: use a script file
        f = paths.ROOT / "results" / ".driver_import_check.py"
        f.parent.mkdir(exist_ok=True)
        f.write_text(script)
        try:
            r = subprocess.run([sys.executable, "/usr/bin/yade", "-n", "-x", str(f)], capture_output=True, text=True,
                               timeout=120, cwd=paths.ROOT)
        finally:
            f.unlink(missing_ok=True)
    assert "DRIVER True 0" in r.stdout, r.stdout[-2000:] + r.stderr[-2000:]


if __name__ == "__main__":
    sys.exit(pytest.main([__file__]))


def test_every_module_has_a_layer_and_the_readme_shows_them():
    """The layers are listed once, in drystone/layers.py; the maintainer's guide's Layout table
    is generated from that list (python -m drystone layout --update-docs)."""
    for mod, _ in _modules():
        layer_of(mod)
    assert [k.rank for k in LAYERS] == list(range(len(LAYERS)))
    guide = (paths.DOCS / "maintainers-guide.md").read_text()
    assert readme_with_layout(guide) == guide, \
        "docs/maintainers-guide.md's Layout table is stale: python -m drystone layout --update-docs"
