"""The documentation's generated tables (drystone/studies/readme_tables.py) on synthetic results,
and the repository's README.md and docs/*.md: every block known, closed and placed once, the
maintainer's guide listing every block, README's summary table quoting only generated numbers."""
import re

import json

import pytest

from drystone import paths
from drystone.studies import readme_tables as rt
from drystone.studies.tilt import study as tilt
from test_tilt_report import fake_run

README = """intro
<!-- begin:tilt -->
old hand-copied numbers 14.78
<!-- end:tilt -->
middle
<!-- begin:sacsayhuaman_table3 -->
placeholder: run make sacsayhuaman
<!-- end:sacsayhuaman_table3 -->
end
"""


def _tilt_results(results):
    seeds, ext = results / "tilt" / "seeds", results / "tilt" / "extruded"
    for k, (a, ra, b, rb) in enumerate([(14.0, 14.6, 15.0, 15.3), (13.5, 14.1, 14.9, 15.1)]):
        fake_run(seeds, f"seed_{k}", k, a, drop=ra)
        fake_run(ext, f"seed_{k}", k, b, drop=rb)
    tilt.build(seeds, results / "r", results / "n", results / "tilt", figures=False, extruded=ext)


def test_blocks_replaced_from_reports_missing_ones_left_and_said(tmp_path):
    _tilt_results(tmp_path)
    new, done, skipped = rt.update(README, tmp_path)
    assert done == ["tilt"] and len(skipped) == 1 and "sacsayhuaman_table3" in skipped[0]
    assert "14.78" not in new and "placeholder: run make sacsayhuaman" in new
    assert "15.30, 15.10: mean 15.20" in new and "results/tilt/summary.json" in new
    assert new.startswith("intro\n<!-- begin:tilt -->\n|") and new.endswith("<!-- end:sacsayhuaman_table3 -->\nend\n")
    again, _, _ = rt.update(new, tmp_path)
    assert again == new  # idempotent


def test_table_taken_from_a_report_heading(tmp_path):
    (tmp_path / "sacsayhuaman").mkdir()
    (tmp_path / "sacsayhuaman" / "report.md").write_text(
        "# S\n\n## Sines\n\n| a |\n|---|\n| 1 |\n\n## Earthquake records: Table 3 (§5.4)\n\ntext\n\n"
        "| record | pga |\n|---|---|\n| paruro | 0.2 |\n\nafter\n| x |\n")
    new, done, _ = rt.update(README, tmp_path)
    assert done == ["sacsayhuaman_table3"]
    assert "| record | pga |\n|---|---|\n| paruro | 0.2 |\n\n_Generated" in new and "| x |" not in new


def test_unknown_or_unclosed_blocks_are_errors(tmp_path):
    with pytest.raises(ValueError, match="unknown"):
        rt.update("<!-- begin:nope -->\nx\n<!-- end:nope -->\n", tmp_path)
    with pytest.raises(ValueError, match="without"):
        rt.update("<!-- begin:tilt -->\nx\n", tmp_path)


def test_cli_check_and_write(tmp_path, capsys):
    _tilt_results(tmp_path)
    readme = tmp_path / "README.md"
    readme.write_text(README)
    assert rt.main([str(readme), "--results", str(tmp_path), "--check"]) == 1
    assert readme.read_text() == README
    assert rt.main([str(readme), "--results", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "tilt: generated" in out and "skipped sacsayhuaman_table3" in out
    assert rt.main([str(readme), "--results", str(tmp_path), "--check"]) == 0


def test_repository_blocks_are_known_closed_and_each_placed_once():
    """README.md and docs/*.md: every marked block has a generator and an end marker, and
    every block of BLOCKS is in exactly one file (make docs warns about a block in none)."""
    placed = []
    for path in rt.documents():
        text = path.read_text()
        names = rt.BEGIN.findall(text)
        assert set(names) <= set(rt.BLOCKS), path
        assert [m.group(2) for m in rt.MARK.finditer(text)] == names, f"{path}: a block without its end"
        placed += names
    twice = sorted({n for n in placed if placed.count(n) > 1})
    nowhere = sorted(set(rt.BLOCKS) - set(placed))
    assert not twice and not nowhere, f"each generated block belongs in exactly one page: in two {twice}, in none {nowhere}"
    assert rt.unplaced([p.read_text() for p in rt.documents()]) == []


def test_maintainers_guide_lists_every_block():
    """The "Generated tables" section names every block of BLOCKS (derived, so the list cannot
    fall behind the code again: it once named 5 of 10)."""
    text = (paths.DOCS / "maintainers-guide.md").read_text()
    section = text.split("\n## Generated tables\n", 1)[1].split("\n## ", 1)[0]
    listed = set(re.findall(r"^\| `([a-z_0-9]+)` \|", section, re.M))
    assert listed == set(rt.BLOCKS)


def _generated_text() -> str:
    return "\n".join(m.group(3) for p in rt.documents() for m in rt.MARK.finditer(p.read_text()))


def test_readme_summary_quotes_generated_numbers():
    """README's "What the papers' comparison shows" table types no number of its own: every
    number in its paper and package columns appears in a generated block of the docs."""
    readme = (paths.ROOT / "README.md").read_text()
    section = readme.split("\n## What the papers' comparison shows\n", 1)[1].split("\n## ", 1)[0]
    rows = [ln for ln in section.splitlines() if ln.startswith("| ") and not ln.startswith("| what")]
    generated = set(re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", _generated_text()))
    numbers = []
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        for cell in cells[1:3]:
            cell = re.sub(r"atan\([^)]*\)|W/\(K_n A\)|K_n|F_t/F_n|\(one core\)|8 cores", "", cell)
            numbers += re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", cell)
    assert len(numbers) >= 15
    missing = sorted(set(numbers) - generated)
    assert not missing, f"README summary numbers found in no generated block: {missing}"


def test_generated_blocks_speak_to_users():
    """No generated block refers to internal issue numbers (bench.json's goal sentence did)."""
    assert not re.search(r"\bissue", _generated_text(), re.I)
    said = rt._plain("compiled step 0.21 ms/step, 7.6x the issue's 1.6 ms/step (goal >= 6x: met)")
    assert "issue" not in said and "the 1.6 ms/step of the uncompiled step it replaced" in said


def test_cli_updates_every_document_and_warns_about_unplaced_blocks(tmp_path, capsys, monkeypatch):
    """Without file arguments the command updates README.md and docs/*.md; a block of BLOCKS
    in none of them is named in a warning; --check looks at every file."""
    _tilt_results(tmp_path)
    root = tmp_path / "repo"
    (root / "docs").mkdir(parents=True)
    (root / "README.md").write_text("front page\n")
    (root / "docs" / "page.md").write_text(README)
    monkeypatch.setattr(rt.paths, "ROOT", root)
    assert rt.documents() == [root / "README.md", root / "docs" / "page.md"]
    assert rt.main(["--results", str(tmp_path), "--check"]) == 1
    assert rt.main(["--results", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert "page.md: tilt: generated" in out and "15.30, 15.10: mean 15.20" in (root / "docs" / "page.md").read_text()
    assert "warning: block 'verification' is in none of README.md, docs/page.md" in err
    assert (root / "README.md").read_text() == "front page\n"
    assert rt.main(["--results", str(tmp_path), "--check"]) == 0


def test_fragility_block_keeps_the_preliminary_warning(tmp_path):
    """The fragility block carries the run count, the fit table and the cost line, and the
    report's warning when the fit is on a subset of the plan (never a bare table)."""
    (tmp_path / "fragility").mkdir()
    report = ("# F\n\n## What ran\n\n* Runs: 220 planned = 22 x 10; 40 finished, 0 failed, 180 not run.\n\n"
              "## Fragility curves: P(DS | PGA)\n\n**Preliminary: fitted on the 40 finished runs of 220.**\n\n"
              "| DS | theta |\n|---|---|\n| DS1 | 0.8 |\n\n![f](f.png)\n\n## Cost\n\n"
              "Measured on this machine (40 runs): 28 s per run.\n")
    (tmp_path / "fragility" / "report.md").write_text(report)
    block = rt.fragility(tmp_path)
    assert block.startswith("Runs: 220 planned = 22 x 10; 40 finished")
    assert "**Preliminary: fitted on the 40 finished runs of 220.**" in block
    assert "| DS1 | 0.8 |" in block and "28 s per run" in block and "results/fragility/report.md" in block
    full = block.replace("**Preliminary", "").count("Preliminary")
    assert full == 0
    (tmp_path / "fragility" / "report.md").write_text(report.replace("**Preliminary: fitted on the 40 finished runs "
                                                                     "of 220.**\n\n", ""))
    assert "Preliminary" not in rt.fragility(tmp_path)


def test_limit_dem_block_takes_both_tables(tmp_path):
    """The limit_dem block: the tilt-table and shape tables of results/limit_dem/report.md;
    missing report: left as it is."""
    with pytest.raises(rt.Missing):
        rt.limit_dem(tmp_path)
    (tmp_path / "limit_dem").mkdir()
    (tmp_path / "limit_dem" / "report.md").write_text(
        "# t\n\n## Tilt-table walls\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n## Shape study's walls\n\n"
        "| c |\n|---|\n| 3 |\n")
    out = rt.limit_dem(tmp_path)
    assert "| 1 | 2 |" in out and "| 3 |" in out and "results/limit_dem/report.md" in out
    assert "Joint compliance" in out and "not run" in out
    with open(tmp_path / "limit_dem" / "report.md", "a") as f:
        f.write("\n## Joint compliance: the DEM at K_n × 10 and × 100\n\n| k |\n|---|\n| 4 |\n\nDEM: how.\n")
    out = rt.limit_dem(tmp_path)
    assert "| 4 |" in out and "DEM: how." in out and "not run" not in out


def test_limit_dem_reads_the_published_tilt_angles():
    """The tilt study's per-seed DEM angles as its generated table lists them (seeds named in
    the row, one angle per seed, onset below reaction drop)."""
    from drystone.studies import limit_dem

    dem = limit_dem.tilt_dem_angles()
    assert set(dem) == {"constant", "varying"} and dem["constant"] and dem["varying"]
    for group in dem.values():
        for onset, drop in group.values():
            assert 0 < onset < drop < 45
