"""The package's layers depend one way (README, Layout): geometry and motions -> core ->
yade_scripts -> postprocess -> studies, with runner, sweep, cli, bench and free_decay on top.
Checked on the import statements of every module (ast), wherever they are in the module."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import requires_yade
from drystone import paths

LEAVES = {"drystone", "drystone.paths", "drystone.units", "drystone.libm", "drystone.inputfiles"}
CORE = {"drystone.case", "drystone.resolve", "drystone.contact", "drystone.overlap", "drystone.loading",
        "drystone.collapse", "drystone.timestep", "drystone.stability", "drystone.modal", "drystone.rotations",
        "drystone.provenance", "drystone.simulate", "drystone.tomlio", "drystone.analytic", "drystone.spec",
        "drystone.stages", "drystone.contact_step"}
TOP = {"drystone.runner", "drystone.sweep", "drystone.cli", "drystone.bench", "drystone.free_decay",
       "drystone.__main__"}


def _layer(mod: str) -> int:
    if mod in LEAVES:
        return 0
    if mod.startswith(("drystone.geometry", "drystone.motions")):
        return 1
    if mod in CORE:
        return 2
    if mod.startswith("drystone.yade_scripts"):
        return 3
    if mod.startswith("drystone.postprocess"):
        return 4
    if mod in TOP:
        return 5
    if mod.startswith(("drystone.studies", "drystone.crosscheck")):
        return 6
    raise AssertionError(f"module {mod} has no layer: add it to tests/test_layers.py")


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


def test_every_import_goes_down_the_layers():
    bad = []
    for mod, path in _modules():
        here = _layer(mod)
        for name in _imports(mod, path):
            t = _target(name)
            if t is None or t == mod or t.startswith(mod + "."):
                continue
            if _layer(t) > here:
                bad.append(f"{mod} (layer {here}) imports {t} (layer {_layer(t)})")
    assert not bad, "\n".join(bad)


def test_the_layer_rule_catches_an_upward_import(tmp_path):
    """The check itself can fail: a geometry module importing the runner is caught."""
    assert _layer("drystone.geometry.blockfile") < _layer("drystone.runner")
    assert _target("drystone.runner.run") == "drystone.runner"


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
