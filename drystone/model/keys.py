"""What a case key is (``Key``: default, unit, meaning, type and range), the marker of a
required key and the error of a case file: the leaf the case model's modules build on
(drystone/model/case.py declares the sections' keys, drystone/model/stages.py each stage
type's), so that neither imports the other for them.
"""
from __future__ import annotations

from dataclasses import dataclass

#: the default of a key a case must give
REQUIRED = object()


class CaseError(ValueError):
    """A case file problem; the message names the file and key."""


@dataclass(frozen=True)
class Key:
    """One case key: ``default`` (or REQUIRED), ``unit``, ``meaning``; the value's type(s)
    ``kind``, its allowed ``choices``, and whether it must be > 0 (``positive``) or >= 0
    (``nonneg``)."""

    default: object
    unit: str
    meaning: str
    kind: type | tuple = float
    choices: tuple = ()
    positive: bool = False  # > 0
    nonneg: bool = False  # >= 0
