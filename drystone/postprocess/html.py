"""Self-contained HTML pages: one file, its figures embedded, no external CSS, script or font.

The run report (drystone/postprocess/report.py) and the studies' report.html
(drystone/postprocess/markdown.py) are built from these pieces: ``page`` (the document
with its style sheet inline), ``image`` (a PNG as a ``data:`` URI), ``table`` and
``esc``. Nothing here fetches anything: a figure that is not a local file is named, not
linked.
"""
from __future__ import annotations

import base64
import html
from pathlib import Path

STYLE = """
body { font-family: sans-serif; max-width: 72em; margin: 1.5em auto; padding: 0 1em; line-height: 1.4; color: #222; }
h1 { font-size: 1.6em; border-bottom: 2px solid #888; padding-bottom: 0.2em; }
h2 { font-size: 1.3em; border-bottom: 1px solid #ccc; margin-top: 1.6em; }
h3 { font-size: 1.1em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.9em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.5em; text-align: left; vertical-align: top; }
th { background: #eee; }
td.num { text-align: right; font-family: monospace; }
pre { background: #f6f6f6; border: 1px solid #ddd; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
code { background: #f2f2f2; padding: 0 0.2em; }
img { max-width: 100%; height: auto; }
figure { margin: 1em 0; }
figcaption { font-size: 0.85em; color: #555; }
.assumed { background: #fff4d6; border-left: 4px solid #e0a000; padding: 0.4em 0.8em; }
.flag { background: #e0a000; color: #fff; font-weight: bold; font-size: 0.75em; padding: 0.05em 0.35em;
        border-radius: 0.2em; }
.warn { color: #a00; font-weight: bold; }
.missing { color: #a00; font-style: italic; }
"""


def esc(x) -> str:
    """``x`` as HTML text (quotes escaped too)."""
    return html.escape(str(x), quote=True)


def page(title: str, body: str) -> str:
    """A complete HTML document: ``title`` (plain text) and ``body`` (HTML)."""
    return (f'<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n<title>{esc(title)}</title>\n'
            f"<style>{STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n")


MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif", ".svg": "image/svg+xml"}


def data_uri(path: Path) -> str:
    """The file at ``path`` as a ``data:`` URI (base64)."""
    path = Path(path)
    mime = MIME.get(path.suffix.lower(), "application/octet-stream")
    return f"data:{mime};base64," + base64.b64encode(path.read_bytes()).decode("ascii")


def image(path: Path, alt: str = "", caption: str | None = None) -> str:
    """A figure with the image embedded; a missing file is named instead (nothing linked)."""
    path = Path(path)
    if not path.is_file() or path.suffix.lower() not in MIME:
        return f'<p class="missing">figure not available: {esc(path.name)}{(" (" + esc(alt) + ")") if alt else ""}</p>'
    cap = f"<figcaption>{esc(caption)}</figcaption>" if caption else ""
    return f'<figure><img src="{data_uri(path)}" alt="{esc(alt or path.name)}">{cap}</figure>'


def _cell(v) -> str:
    if isinstance(v, float):
        return f'<td class="num">{v:.6g}</td>'
    if isinstance(v, int) and not isinstance(v, bool):
        return f'<td class="num">{v}</td>'
    return f"<td>{esc('' if v is None else v)}</td>"


def table(headers: list[str], rows: list[list], raw: bool = False) -> str:
    """An HTML table; cells are escaped text (``raw``: HTML as given), floats to 6 digits."""
    head = "".join(f"<th>{esc(h)}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" if raw else _cell(c) for c in r) + "</tr>\n" for r in rows)
    return f"<table>\n<thead><tr>{head}</tr></thead>\n<tbody>\n{body}</tbody>\n</table>\n"
