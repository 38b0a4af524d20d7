"""Where things are: the one module that knows the repository layout."""
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
ROOT = PACKAGE.parent
RESULTS = ROOT / "results"
DOCS = ROOT / "docs"  # the user documentation (README.md is its front page)
CASES = ROOT / "cases"
DATA = ROOT / "data"
