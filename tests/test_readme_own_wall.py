"""README's "Your own wall" section: every command block (```sh) runs as written (issue 25):
the block file, a stone of parts, outline files, a DXF drawing, scanned meshes and the
polygonal generator, each from the repository root. The runs' folders (``results/...``)
are moved into a temporary folder, and each run must leave a finished run there
(summary.json and histories.npz); ``validate`` must pass."""
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import requires_yade

ROOT = Path(__file__).resolve().parents[1]
pytestmark = [requires_yade, pytest.mark.yade]


def section_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    start = text.index("\n## Your own wall\n")
    end = text.index("\n## ", start + 1)
    blocks = re.findall(r"```sh\n(.*?)```", text[start:end], re.S)
    return [line for b in blocks for line in b.splitlines() if line.strip()]


def test_section_covers_every_input_path():
    cmds = " ".join(section_commands())
    for path in ("one_block", "l_stone", "outline_wall", "dxf_wall", "scanned_stones", "polygonal_wall"):
        assert f"cases/examples/{path}" in cmds


@pytest.mark.parametrize("command", section_commands())
def test_readme_command_runs(command, tmp_path):
    argv = shlex.split(command)
    assert argv[0] == ".venv/bin/python", "README commands use the project's interpreter"
    argv[0] = sys.executable
    out = None
    if "--out" in argv:
        k = argv.index("--out") + 1
        assert argv[k].startswith("results/")
        out = tmp_path / argv[k]
        argv[k] = str(out)
    r = subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    if out is not None:
        summary = json.loads((out / "summary.json").read_text())
        assert (out / "histories.npz").is_file() and summary["run"]["steps"] > 0
