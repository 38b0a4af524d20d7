"""The user guide's "Your own wall" section (docs/user-guide.md) shows every way to bring a
wall with a command that runs: the block file, a stone of parts, outline files, a DXF
drawing, scanned meshes and the generators, each from the repository root. The commands
themselves are run by tests/test_docs_runnable.py (every block marked runnable); this
checks that the section's runnable blocks cover every input path, and that README's first
wall points to the section."""
import re

from docblocks import ROOT, blocks

GUIDE = ROOT / "docs" / "user-guide.md"


def section_blocks():
    text = GUIDE.read_text()
    start = text.index("\n## Your own wall\n")
    end = text.index("\n## ", start + 1)
    first, last = text[:start].count("\n") + 1, text[:end].count("\n") + 1
    return [b for b in blocks(GUIDE) if first <= b.line <= last]


def test_section_covers_every_input_path():
    runnable = " ".join(b.code for b in section_blocks() if b.runnable)
    for path in ("one_block", "l_stone", "outline_wall", "dxf_wall", "scanned_stones", "polygonal_wall"):
        assert f"cases/examples/{path}" in runnable, path
    assert "drystone.geometry validate" in runnable and "irregular_wall" in runnable


def test_readme_first_wall_links_to_the_section():
    readme = (ROOT / "README.md").read_text()
    assert "## Your first wall" in readme
    assert re.search(r"\]\(docs/user-guide\.md#your-own-wall\)", readme)
