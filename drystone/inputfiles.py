"""Reading the user's input files (case and sweep files in TOML, block files in JSON): the
one home for it. Every way a file can be unreadable becomes one error naming the file,
raised as the caller's error class (CaseError, GeometryError), never a traceback:
missing or unreadable, not UTF-8 text, not valid TOML/JSON, nested deeper than
``MAX_DEPTH``, or holding an integer outside TOML's 64-bit range (``INT_RANGE``; Python
would otherwise carry a 5000-digit integer until a float conversion overflows). A leaf
module: it imports nothing of the package.
"""
from __future__ import annotations

import json
import tomllib
from pathlib import Path

#: tables/arrays nested deeper than this are refused (case, sweep and block files need 4)
MAX_DEPTH = 32
#: integers are 64-bit signed, as the TOML specification requires of its readers
INT_RANGE = (-2 ** 63, 2 ** 63 - 1)


def read_text(path, error=ValueError, what: str = "file") -> str:
    """The UTF-8 text of ``path``; ``error`` (the caller's exception class) names the file
    when it is missing, not a regular file, unreadable or not UTF-8."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except FileNotFoundError:
        raise error(f"{p}: {what} not found") from None
    except IsADirectoryError:
        raise error(f"{p}: is a folder, not a {what}") from None
    except OSError as exc:
        raise error(f"{p}: cannot read the {what}: {exc.strerror or exc}") from None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{p}: not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); "
                    f"save the {what} as UTF-8") from None


def load_toml(path, error=ValueError, what: str = "file") -> dict:
    """Parse a TOML file (``read_text`` first); the errors of ``check_values`` too."""
    return _load(path, error, what, "TOML", tomllib.loads)


def load_json(path, error=ValueError, what: str = "file"):
    """Parse a JSON file (``read_text`` first); the errors of ``check_values`` too."""
    return _load(path, error, what, "JSON", json.loads)


def _load(path, error, what: str, kind: str, parse):
    """``parse`` the text of ``path``; every failure one ``error`` naming the file."""
    p = Path(path)
    text = read_text(p, error, what)
    try:
        data = parse(text)
    except RecursionError:
        raise error(f"{p}: not valid {kind}: nested deeper than Python can read") from None
    except json.JSONDecodeError as exc:
        raise error(f"{p}: not valid {kind}: line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    except ValueError as exc:  # TOMLDecodeError, and Python's limit on the digits of an integer
        raise error(f"{p}: not valid {kind}: {_why(exc)}") from None
    check_values(data, str(p), error)
    return data


def _why(exc: ValueError) -> str:
    """A parser's message, or what Python's limit on an integer's digits means here."""
    if "integer string conversion" in str(exc):
        return "an integer with thousands of digits (a large number is written as a float, e.g. 1e30)"
    return str(exc)


def check_values(data, where: str, error=ValueError) -> None:
    """Refuse nesting deeper than ``MAX_DEPTH`` and integers outside ``INT_RANGE``, naming
    the key path (iterative: no recursion limit of its own)."""
    lo, hi = INT_RANGE
    todo = [(data, "", 0)]
    while todo:
        node, key, depth = todo.pop()
        if depth > MAX_DEPTH:
            raise error(f"{where}: {key or 'the top level'}: nested more than {MAX_DEPTH} levels deep")
        if isinstance(node, dict):
            todo += [(v, f"{key}.{k}" if key else str(k), depth + 1) for k, v in node.items()]
        elif isinstance(node, list):
            todo += [(v, f"{key}[{i}]", depth + 1) for i, v in enumerate(node)]
        elif isinstance(node, int) and not isinstance(node, bool) and not lo <= node <= hi:
            raise error(f"{where}: '{key}': integer out of range (64-bit: {lo} .. {hi}; "
                        f"a larger number is written as a float, e.g. 1e30)")
