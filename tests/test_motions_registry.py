"""The record formats' registry (drystone/motions/readers.py, issue 24 item 5): each format is
one entry holding its sniffing and its reading, and the format names, the detection, the
dispatch and the documentation all come from it."""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from drystone import paths
from drystone.motions import readers
from drystone.motions.record import Record


def test_every_entry_sniffs_and_reads_and_formats_are_its_names():
    names = [f.name for f in readers.REGISTRY]
    assert readers.FORMATS == tuple(names)
    assert len(set(names)) == len(names)
    for f in readers.REGISTRY:
        assert isinstance(f, readers.RecordFormat)
        assert callable(f.sniff) and callable(f.read), f.name
        assert f.description.strip(), f.name
        assert all(e.startswith(".") and e == e.lower() for e in f.extensions), f.name
        assert readers.record_format(f.name) is f
        assert f'``"{f.name}"``' in readers.__doc__  # the module's format list comes from it


def test_a_format_added_to_the_registry_is_detected_and_read(tmp_path, monkeypatch):
    """Adding a format is one entry: detect_format sniffs it in its place and read_all
    dispatches to it; an extension it claims wins over every sniff."""
    def read_demo(path, dt=None, units=None, **_):
        return [Record(np.zeros(3), 0.5, component="NS", source=str(path))]

    demo = readers.RecordFormat("demo", "a test format", lambda p: p.text.startswith("DEMO"), read_demo,
                                extensions=(".dmo",))
    monkeypatch.setattr(readers, "REGISTRY", (demo,) + readers.REGISTRY)
    f = tmp_path / "a.txt"
    f.write_text("DEMO\n1\n2\n")
    assert readers.detect_format(f) == "demo"
    assert readers.read(f).dt == 0.5
    g = tmp_path / "b.dmo"
    g.write_text("# dt = 0.01\n1\n2\n")
    assert readers.detect_format(g) == "demo"
    assert readers.detect_format(tmp_path / "a.at2") == "peer"  # claimed by peer's extension, unread
    monkeypatch.setattr(readers, "REGISTRY", (replace(demo, extensions=()),) + readers.REGISTRY[1:])
    assert readers.detect_format(g) == "obspy"  # .dmo is not a text extension


def test_the_docs_table_lists_the_registry():
    """docs/motions.md's table of formats has one row per registry entry."""
    text = (paths.ROOT / "docs" / "motions.md").read_text()
    table = re.search(r"^\| format \| file \| notes \|\n\|[-|]+\|\n((?:\|.*\n)+)", text, flags=re.M)
    assert table, "docs/motions.md has no '| format | file | notes |' table"
    rows = re.findall(r"^\| `([a-z0-9_]+)` \|", table.group(1), flags=re.M)
    assert sorted(rows) == sorted(readers.FORMATS)
