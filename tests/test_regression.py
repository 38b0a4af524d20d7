"""Regression against stored histories: gravity4, settlement4 and a slab sliding under a base
sine, re-run on one thread, give the positions, kinetic energy and forces of the named
contact stored in tests/data/reference/ (written by tests/make_reference.py, which records
the commit they came from).

Each quantity is compared with its scale in the reference: the positions with the largest
displacement from the first sample, the kinetic energy with its largest value, both
contact forces with the largest normal force; tolerance tolerances.REGRESSION_REL (one
thread is bitwise reproducible on one machine; the tolerance covers the round-off of
another machine, derivation there). After a change of results that is intended,
regenerate the files: ``.venv/bin/python tests/make_reference.py``.
"""
import numpy as np
import pytest

import make_reference as mr
import tolerances as tol
from conftest import requires_yade

pytestmark = [requires_yade, pytest.mark.yade]


def scales(ref: dict) -> dict:
    """The scale each stored quantity is compared with (module docstring)."""
    force = np.abs(ref["fn"]).max()
    return {"t": ref["t"][-1], "pos": np.abs(ref["pos"] - ref["pos"][0]).max(), "kinetic": ref["kinetic"].max(),
            "fn": force, "ft": force}


@pytest.mark.parametrize("name", list(mr.CASES))
def test_history_matches_the_stored_reference(outdir, name):
    ref, meta = mr.load(name)
    assert meta["threads"] == 1 and meta["case"] == name
    new, _ = mr.run(name, outdir)
    for key, scale in scales(ref).items():
        assert new[key].shape == ref[key].shape, f"{name}: {key} has shape {new[key].shape}, stored {ref[key].shape}"
        err = np.abs(new[key] - ref[key]).reshape(len(ref["t"]), -1).max(axis=1)
        k = int(np.argmax(err))
        assert err[k] <= tol.REGRESSION_REL * scale, (
            f"{name}: {key} differs by {err[k]:.3g} ({err[k] / scale:.2g} of its scale {scale:.3g}) at t = "
            f"{ref['t'][k]:.4f} s from the reference of commit {meta['git']['commit']}")
