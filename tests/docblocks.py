"""The code blocks of the documentation (README.md and docs/*.md), for the tests that keep
them from going stale (test_readme_snippets.py checks every block without running it,
test_docs_runnable.py runs the blocks marked runnable).

A block is a fenced code block: a line ```` ```LANG ```` alone, its lines, a line ```` ``` ````
alone. The line directly above the opening fence may mark it:

* ``<!-- runnable -->``: a ``sh`` or ``python`` block the reader can paste; the test runs it
  (``sh``: each line a command starting with ``.venv/bin/python``, writing under
  ``results/``);
* ``<!-- file: PATH -->``: the block is the content of the file PATH (relative to the
  repository root, where the reader saves it); the test writes it there before it runs the
  blocks that follow.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OPEN = re.compile(r"^```([\w+-]*)\s*$")
CLOSE = re.compile(r"^```\s*$")
MARK = re.compile(r"^<!-- (runnable|file: (\S+)) -->$")


@dataclass(frozen=True)
class Block:
    doc: Path        # the Markdown file
    line: int        # line number of the opening fence (1-based)
    lang: str        # the fence's language ("" if none)
    code: str        # the block's text, ending with a newline
    runnable: bool   # marked <!-- runnable -->
    file: str | None  # the PATH of a <!-- file: PATH --> mark

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(ROOT)}:{self.line}"


def documents() -> list[Path]:
    """README.md and every page of docs/ (the files a reader follows)."""
    return [ROOT / "README.md"] + sorted((ROOT / "docs").glob("*.md"))


def blocks(doc: Path) -> list[Block]:
    """The fenced code blocks of ``doc``, in order; an unclosed fence is an error."""
    lines = doc.read_text().splitlines()
    out, k = [], 0
    while k < len(lines):
        m = OPEN.match(lines[k])
        if not m:
            k += 1
            continue
        end = next((j for j in range(k + 1, len(lines)) if CLOSE.match(lines[j])), None)
        if end is None:
            raise ValueError(f"{doc}:{k + 1}: code block without its closing fence")
        mark = MARK.match(lines[k - 1]) if k else None
        out.append(Block(doc, k + 1, m.group(1), "\n".join(lines[k + 1:end]) + "\n",
                         bool(mark) and mark.group(1) == "runnable", mark.group(2) if mark else None))
        k = end + 1
    return out


def all_blocks() -> list[Block]:
    return [b for doc in documents() for b in blocks(doc)]
