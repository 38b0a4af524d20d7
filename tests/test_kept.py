"""drystone/kept.py: a process's results by their inputs, copies returned, the oldest dropped."""
from drystone.kept import Kept


def test_kept_computes_once_and_returns_copies():
    kept, calls = Kept(2), []

    def compute():
        calls.append(1)
        return {"angles": [1.0, 2.0]}

    first = kept.get("wall", compute)
    first["angles"].append(3.0)  # a caller's change is its own
    assert kept.get("wall", compute) == {"angles": [1.0, 2.0]}
    assert len(calls) == 1
    assert kept.get("other") is None and "other" not in kept


def test_kept_drops_the_oldest_past_its_size():
    kept = Kept(2)
    for k in "abc":
        kept.put(k, k.upper())
    assert "a" not in kept and kept.get("b") == "B" and kept.get("c") == "C" and len(kept) == 2
    kept.put("b", "B2")  # put again: the newest
    kept.put("d", "D")
    assert "c" not in kept and kept.get("b") == "B2"
