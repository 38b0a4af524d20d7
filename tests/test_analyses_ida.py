"""Hunt-and-fill (drystone/analyses/ida.py) against fake runners: a monotonic wall, one
whose response is not monotonic (it collapses inside a window of intensities below a
level at which it stands: "resurrection" above), a wall standing at the cap, a wall that
collapses at the first run, the run budget, and replay from partial observations."""
import pytest

from drystone.analyses import ida


def threshold(x0):
    return lambda g: g >= x0


def test_monotonic_bracket_contains_the_threshold():
    p = ida.Params(start=0.1, factor=2.0, cap=3.0, tolerance=0.05, fill=0.25)
    s, order = ida.search(threshold(1.37), p)
    assert s.status == "bracketed" and s.done
    lo, hi = s.bracket
    assert lo < 1.37 <= hi and hi - lo <= p.tolerance + 1e-9
    assert s.non_monotonic == []
    assert order[:5] == [0.1, 0.2, 0.4, 0.8, 1.6]  # geometric hunt up to the first collapse
    assert len(order) == len(set(order))  # nothing run twice
    # fill-in: no gap below the collapse wider than fill x hi is left
    levels = [0.0] + sorted(g for g in order if g < hi) + [hi]
    assert max(b - a for a, b in zip(levels, levels[1:])) <= p.fill * hi + 1e-9


def test_without_fill_in_the_search_stops_at_the_bracket():
    p = ida.Params(fill=None)
    s, order = ida.search(threshold(1.37), p)
    s2, order2 = ida.search(threshold(1.37), ida.Params(fill=0.25))
    assert s.bracket == s2.bracket and len(order) < len(order2)


def test_non_monotonic_response_keeps_the_lowest_collapse():
    """Collapse in [1.0, 1.25) and from 2.0 g; standing at 1.6 g (hunt) and just below 2 g."""
    collapses = lambda g: 1.0 <= g < 1.25 or g >= 2.0  # noqa: E731
    p = ida.Params(start=0.1, factor=2.0, cap=3.0, tolerance=0.05, fill=0.25)
    s, order = ida.search(collapses, p)
    lo, hi = s.bracket
    assert lo < 1.0 <= hi and hi - lo <= p.tolerance + 1e-9
    assert 1.6 in s.non_monotonic  # stood above the lowest collapse: reported
    assert all(g > hi and not collapses(g) for g in s.non_monotonic)
    # the hunt alone would have bracketed 2.0 g: the fill-in found the lower window
    s_nofill, _ = ida.search(collapses, ida.Params(fill=None))
    assert s_nofill.bracket[0] < 2.0 <= s_nofill.bracket[1] and s_nofill.non_monotonic == []


def test_censored_at_the_cap():
    s, order = ida.search(lambda g: False, ida.Params(cap=3.0))
    assert s.status == "censored" and s.censored_at_g == 3.0 and s.bracket is None
    assert order[-1] == 3.0 and order == sorted(order)


def test_collapse_at_the_first_run_brackets_from_zero():
    s, order = ida.search(threshold(0.03), ida.Params(start=0.1, tolerance=0.01))
    lo, hi = s.bracket
    assert order[0] == 0.1 and lo < 0.03 <= hi and hi - lo <= 0.01 + 1e-9


def test_budget_stops_a_search():
    s, order = ida.search(threshold(1.37), ida.Params(max_runs=4))
    assert s.status == "budget" and len(order) == 4 and s.done


def test_replay_gives_the_same_next_intensity():
    p = ida.Params()
    _, order = ida.search(threshold(0.77), p)
    observed = {}
    for g in order:  # a search interrupted after any run continues where it stopped
        assert ida.step(observed, p).next_g == g
        observed[g] = g >= 0.77
    assert ida.step(observed, p).done


@pytest.mark.parametrize("bad", [dict(factor=1.0), dict(tolerance=0.0), dict(start=-1.0), dict(fill=-0.1)])
def test_bad_parameters_are_refused(bad):
    with pytest.raises(ValueError):
        ida.step({}, ida.Params(**bad))


@pytest.mark.parametrize("probes", [1, 2, 3])
@pytest.mark.parametrize("x0", [0.03, 0.77, 1.37])
def test_several_probes_per_round_end_at_the_same_rule(probes, x0):
    """Rounds of several runs (ida.plan) bracket the threshold as tightly, in fewer rounds."""
    p = ida.Params(start=0.1, factor=2.0, cap=3.0, tolerance=0.05, fill=0.25)
    observed, rounds = {}, 0
    while True:
        todo = ida.plan(observed, p, probes)
        if not todo:
            break
        assert len(todo) <= probes and not set(todo) & set(observed)
        observed.update({g: g >= x0 for g in todo})
        rounds += 1
    s = ida.step(observed, p)
    lo, hi = s.bracket
    assert lo < x0 <= hi and hi - lo <= p.tolerance + 1e-9 and s.status == "bracketed"
    _, order = ida.search(threshold(x0), p)
    assert rounds <= len(order)
    if probes == 1:
        assert sorted(observed) == sorted(order)
