"""Files written aside and renamed into place: the one home of the package's atomic writes.

A file the package writes is first written to a hidden temporary in the same folder
(``.NAME.tmp-XXXXXXXX.EXT``: same filesystem, so the rename is atomic; the extension kept,
so writers that choose a format by it choose the same one), then renamed over the final
name. A reader sees the old file or the new one, never a truncated one; a failure (a full
disk, a read-only folder) removes the temporary, leaves the old file as it was and raises
``OSError`` whose ``filename`` is the FINAL path, so the one-line message names the file
the user asked for ("error: results/x/report.html: No space left on device"), never the
temporary.

    with atomic.aside(path) as tmp:   # any writer of a path
        meshio.write(tmp, mesh)
    atomic.write_text(path, text)     # text, bytes, matplotlib figures
    atomic.savefig(fig, path, dpi=120)

``TEMP_MARK`` names the temporaries, which ``python -m drystone.clean`` recognises as the
package's own (left behind only by a process killed mid-write). A file written under the
results folder (``paths.RESULTS``) is also listed in its folder's hidden ``MANIFEST``, so that
``make clean`` deletes what the package wrote there and nothing else (a study's report, tables
and figures beside a user's notes).
"""
from __future__ import annotations

import os
import secrets
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

#: the infix of every temporary this module makes (``.NAME.tmp-XXXXXXXX.EXT``)
TEMP_MARK = ".tmp-"
#: the hidden file, in a folder under the results folder, listing the files written there (one name a line)
MANIFEST = ".drystone-written"


def temporary(path: Path) -> Path:
    """A fresh hidden name beside ``path`` for its temporary (same folder, same extension)."""
    p = Path(path)
    return p.parent / f".{p.stem}{TEMP_MARK}{secrets.token_hex(4)}{p.suffix}"


def is_temporary(name: str) -> bool:
    """True for a name ``temporary`` makes."""
    return name.startswith(".") and TEMP_MARK in name


def named(exc: OSError, path: Path) -> OSError:
    """``exc`` (errno and the system's words) re-addressed to ``path``."""
    out = OSError(exc.errno, exc.strerror or str(exc), str(path))
    out.__cause__ = exc
    return out


@contextmanager
def aside(path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; when the block ends without error, rename it
    onto ``path``. On any error the temporary is removed and ``path`` is untouched; an
    OSError is raised again naming ``path`` (see the module's docstring)."""
    p = Path(path)
    tmp = temporary(p)
    try:
        yield tmp
        os.replace(tmp, p)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise named(exc, p) from None
        raise
    record(p)


def record(path: Path) -> None:
    """List ``path`` in its folder's ``MANIFEST`` when it lies under the results folder and
    outside a run's folder (``python -m drystone.clean`` deletes what is listed). Best effort: a manifest that cannot
    be written never fails the write it records (the file is then left by clean, and said)."""
    from drystone import paths

    p = Path(path)
    try:
        p.resolve().relative_to(Path(paths.RESULTS).resolve())
    except (ValueError, OSError):
        return
    if p.parent.name.endswith(".partial") or (p.parent / "spec.json").is_file():
        return  # a run's folder (or one being built): the package's whole, recognised as such
    m = p.parent / MANIFEST
    try:
        if m.is_file() and p.name in m.read_text(errors="replace").splitlines():
            return
        fd = os.open(m, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, (p.name + "\n").encode())
        finally:
            os.close(fd)
    except OSError:
        pass


def listed(folder: Path) -> set[str]:
    """The names ``MANIFEST`` lists in ``folder`` (empty when it has none)."""
    try:
        return set((Path(folder) / MANIFEST).read_text(errors="replace").splitlines()) - {""}
    except OSError:
        return set()


def write_text(path, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    with aside(path) as tmp:
        with open(tmp, "w", encoding=encoding) as f:
            f.write(text)
    return Path(path)


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with aside(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
    return Path(path)


def savefig(fig, path, **kwargs) -> Path:
    """``fig.savefig`` to ``path`` atomically (the format from ``path``'s extension)."""
    p = Path(path)
    kwargs.setdefault("format", p.suffix.lstrip(".") or None)
    with aside(p) as tmp:
        fig.savefig(tmp, **kwargs)
    return p
