"""Where things are: the one module that knows the repository layout."""
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
ROOT = PACKAGE.parent
RESULTS = ROOT / "results"
CASES = ROOT / "cases"
DATA = ROOT / "data"
