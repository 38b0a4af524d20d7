"""Where things are: the one module that knows the repository layout."""
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
CASES = ROOT / "cases"
DATA = ROOT / "data"
