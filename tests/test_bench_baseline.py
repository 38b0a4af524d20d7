"""drystone.bench_baseline: ``bench --baseline COMMIT``, this tree's scale section against an
earlier commit's, back to back (the benches themselves are not run here: a stand-in package
plays a tree's ``python -m drystone bench``)."""
import json
import subprocess

import pytest

from drystone import bench_baseline as bb
from drystone import cli, paths


def rows(ms, walls=(("running_bond", 500), ("polygonal", 500))):
    return [dict(wall=w, size=n, ms_per_step=m, us_per_contact_step=m / 2.0) for (w, n), m in zip(walls, ms)]


def test_compare_gives_both_trees_rounds_and_the_speed_ups():
    """Per wall: both trees' figures in every round, the speed-up of the fastest (theirs' fastest
    over ours') and of the medians; a wall the baseline has not: None (numbers exact in binary)."""
    theirs = [rows([12.0, 20.0], [("running_bond", 500), ("irregular", 500)]), rows([8.0]), rows([16.0])]
    ours = [rows([6.0, 3.0]), rows([4.0, 3.0]), rows([2.0, 3.0])]
    out = bb.compare(theirs, ours)
    assert [(r["wall"], r["size"]) for r in out] == [("running_bond", 500), ("polygonal", 500)]
    rb, poly = out
    assert rb["baseline_ms_per_step"] == [12.0, 8.0, 16.0] and rb["ms_per_step"] == [6.0, 4.0, 2.0]
    assert rb["baseline_us_per_contact_step"] == [6.0, 4.0, 8.0] and rb["us_per_contact_step"] == [3.0, 2.0, 1.0]
    assert rb["speedup_fastest"] == 4.0  # 8 / 2
    assert rb["speedup_median"] == 3.0  # 12 / 4
    assert poly["baseline_ms_per_step"] is None and poly["speedup_fastest"] is None
    assert poly["speedup_median"] is None and poly["ms_per_step"] == [3.0, 3.0, 3.0]


def test_a_name_that_is_no_commit_stops_the_bench_before_anything_runs(capsys):
    bench_json = paths.RESULTS / "bench" / "bench.json"
    before = bench_json.read_bytes() if bench_json.is_file() else None
    assert cli.main(["bench", "--baseline", "no-such-commit-0123"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "'no-such-commit-0123' is not a commit" in err
    assert (bench_json.read_bytes() if bench_json.is_file() else None) == before
    assert cli.main(["bench", "--baseline", "HEAD", "--rounds", "0"]) == 2


def test_the_worktree_holds_the_commit_and_is_removed_after():
    sha = bb.resolve("HEAD")
    assert len(sha) == 40
    with bb.worktree(sha) as tree:
        assert (tree / "drystone" / "__init__.py").is_file()
        head = subprocess.run(["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True)
        assert head.stdout.strip() == sha
    assert not tree.exists()
    listed = subprocess.run(["git", "-C", str(paths.ROOT), "worktree", "list"], capture_output=True, text=True)
    assert str(tree) not in listed.stdout


STAND_IN = """import json, sys
from pathlib import Path
args = sys.argv[1:]
assert args[:3] == ["bench", "--only", "scale"], args
if "fail" in Path.cwd().name:
    print("a failing bench", file=sys.stderr)
    sys.exit(1)
rows = [dict(wall=w, size=n, ms_per_step=5.0, us_per_contact_step=2.5)
        for w in ("running_bond", "polygonal") for n in (40, 500)]
out = Path("results/bench"); out.mkdir(parents=True, exist_ok=True)
(out / "bench.json").write_text(json.dumps({"scale": {"rows": rows}, "argv": args}))
"""


@pytest.mark.parametrize("name", ["tree", "tree_fail"])
def test_a_trees_scale_section_runs_in_its_own_process_with_its_own_package(tmp_path, name):
    """scale_rows runs the tree's own ``python -m drystone`` (its package first on the path) with
    the walls and sizes asked and reads back those rows; a failed bench is one BaselineError."""
    tree = tmp_path / name
    (tree / "drystone").mkdir(parents=True)
    (tree / "drystone" / "__init__.py").write_text("")
    (tree / "drystone" / "__main__.py").write_text(STAND_IN)
    if name.endswith("fail"):
        with pytest.raises(bb.BaselineError, match="a failing bench"):
            bb.scale_rows(tree, [500], ["polygonal"])
        return
    got = bb.scale_rows(tree, [500], ["polygonal"])
    assert [(r["wall"], r["size"]) for r in got] == [("polygonal", 500)]
    argv = json.loads((tree / "results" / "bench" / "bench.json").read_text())["argv"]
    assert argv == ["bench", "--only", "scale", "--sizes", "500", "--walls", "polygonal"]
