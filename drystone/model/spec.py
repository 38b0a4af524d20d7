"""The run specification (spec.json): typed, frozen, versioned.

``Spec`` and ``StageSpec`` are frozen dataclasses built by ``drystone.model.resolve.resolve``;
their nested tables are read-only (mappings as ``MappingProxyType``, arrays as tuples).
For the readers written against the JSON dict, both also give read-only mapping access
(``spec["dt"]``, ``spec.get(...)``, ``"key" in spec``), which returns plain JSON data (a
fresh copy: dicts and lists); new code uses the attributes. A changed spec is a new one
(``Spec.replace``).

Versions: 1 named a stage's type ``kind``, 2 names it ``type``, 3 adds a block's
``parts`` (a stone of several convex parts; its ``vertices`` are then every part's
corners, for extents only; a reader of version 2 would take the stone for their hull), 4
adds ``loads`` (the resolved [[loads]], drystone/model/loads.py; absent when a case has
none, so a spec without loads reads as before). Every reader of a spec of
any version goes through ``upgrade`` (``spec_dict``, ``load_spec``); summary.json's
``inputs.stages`` mirror a spec's stages and are read with ``stage_type``. Core layer: no
YADE, no numpy.
"""
from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

#: spec.json's format name and version (histories.npz and summary.json carry theirs)
SPEC_FORMAT, SPEC_VERSION = "drystone-spec", 4


class SpecError(ValueError):
    """A spec.json this reader cannot read (another format, a newer version, keys missing)."""


# -- upgrade: the one place that knows the old versions ---------------------------------
def upgrade_stage(st: Mapping) -> dict:
    """A spec stage of any version as a version-2 dict (version 1's ``kind`` becomes
    ``type``, in its place); partial stages (summary.json's inputs) are accepted."""
    if "kind" in st and "type" not in st:
        return {("type" if k == "kind" else k): v for k, v in st.items()}
    return dict(st)


def stage_type(st: Mapping) -> str:
    """The type of a spec stage of any version (gravity, settlement, tilt, excitation, rest)."""
    return upgrade_stage(st)["type"]


def upgrade(data: Mapping) -> dict:
    """A spec.json dict of any version as a version-2 dict (a new dict; ``data`` is left as
    it was). No ``format``/``version`` keys (specs written before they existed) means 1."""
    fmt, version = data.get("format", SPEC_FORMAT), data.get("version", 1)
    if fmt != SPEC_FORMAT:
        raise SpecError(f"not a run specification: format {fmt!r} (expected {SPEC_FORMAT!r})")
    if not isinstance(version, int) or isinstance(version, bool) or not 1 <= version <= SPEC_VERSION:
        raise SpecError(f"unsupported spec version {version!r} (this reader: 1 to {SPEC_VERSION})")
    out = {"format": SPEC_FORMAT, "version": SPEC_VERSION}
    out.update((k, v) for k, v in data.items() if k not in ("format", "version"))
    if "stages" in out:
        out["stages"] = [upgrade_stage(st) for st in out["stages"]]
    return out


# -- frozen values ------------------------------------------------------------------------
def freeze(value):
    """A read-only copy of JSON-like data: mappings as MappingProxyType, lists as tuples."""
    if isinstance(value, Spec | StageSpec):
        return value
    if isinstance(value, Mapping):
        return MappingProxyType({k: freeze(v) for k, v in value.items()})
    if isinstance(value, (list, tuple)):
        return tuple(freeze(v) for v in value)
    return value


def thaw(value):
    """Plain JSON data (dicts, lists) from frozen data: a fresh copy, safe to change."""
    if isinstance(value, Spec | StageSpec):
        return value.to_dict()
    if isinstance(value, Mapping):
        return {k: thaw(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [thaw(v) for v in value]
    return value


class _ReadOnlyMapping(Mapping):
    """Mapping access to a frozen dataclass's fields, as plain JSON data; a field that is
    None is absent (as a key the JSON did not have)."""

    __slots__ = ()
    _HEADER: dict = {}

    def __getitem__(self, key):
        if key in self._HEADER:
            return self._HEADER[key]
        if key in self._fields() and getattr(self, key) is not None:
            return thaw(getattr(self, key))
        raise KeyError(key)

    def __iter__(self):
        yield from self._HEADER
        yield from (f for f in self._fields() if getattr(self, f) is not None)

    def __len__(self):
        return sum(1 for _ in self)

    def __contains__(self, key):
        return key in self._HEADER or (key in self._fields() and getattr(self, key) is not None)

    @classmethod
    def _fields(cls) -> tuple[str, ...]:
        return tuple(f.name for f in dataclasses.fields(cls))

    def to_dict(self) -> dict:
        """The JSON form (plain dicts and lists, a fresh copy)."""
        return {k: self[k] for k in self}

    def replace(self, **changes):
        """A copy with ``changes`` (field names) applied; the spec itself never changes."""
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True, eq=True)
class StageSpec(_ReadOnlyMapping):
    """One resolved stage: ``type`` (a key of drystone.model.stages.REGISTRY), absolute ``start``
    and ``end`` (s), and the type's ``params`` (read-only; units in drystone/model/stages.py)."""

    type: str
    start: float
    end: float
    params: Mapping = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "params", freeze(self.params))

    @classmethod
    def from_dict(cls, data: Mapping) -> StageSpec:
        st = upgrade_stage(data)
        return cls(st["type"], st["start"], st["end"], st.get("params", {}))


@dataclass(frozen=True, eq=True)
class Spec(_ReadOnlyMapping):
    """What YADE runs (drystone/yade_scripts/run_case.py) and what post-processing reads:
    SI units, the platform frame. Field order is spec.json's key order."""

    _HEADER = {"format": SPEC_FORMAT, "version": SPEC_VERSION}

    name: str
    out_dir: str  # the run's folder (runner: where it will live; excitation samples lie there)
    law: str  # a contact law of drystone.mechanics.laws.REGISTRY
    detection: str  # native or yade
    dt: float  # s
    dt_critical: float  # s
    dt_critical_detail: Mapping  # the critical contact (drystone/model/timestep.py)
    gravity: float  # m/s^2
    materials: Mapping  # name -> density kg/m^3, kn kt N/m^3, mu, damping
    blocks: tuple  # {id, role, material, vertices m, [parts m,] blocked_dofs}
    joint_overrides: Mapping  # "a-b" (a < b) -> contact properties of that joint
    control_points: tuple  # {name, block, position m}
    stages: tuple  # StageSpec, contiguous from t = 0
    forces: tuple  # {block, force N, start s, end s or None}
    output: Mapping  # interval s, contacts
    collapse_threshold: Mapping  # block id (str) -> m
    onset_rate: float  # m/deg
    onset_window_deg: float  # deg
    stock_shear_area: float  # m^2
    geometry_source: Mapping  # {file, sha256} or {generator}
    excitations: tuple  # per excitation stage: its samples' metadata
    analysis: Mapping  # the case's [analysis]
    loads: tuple | None = None  # {type, params} per [[loads]] (drystone/model/loads.py); None: no loads
    provenance: Mapping | None = None  # set by the runner (drystone/provenance.py)

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name == "stages":
                v = tuple(st if isinstance(st, StageSpec) else StageSpec.from_dict(st) for st in v)
            object.__setattr__(self, f.name, freeze(v))

    @classmethod
    def from_dict(cls, data: Mapping) -> Spec:
        """A Spec from a spec.json dict of any version (``upgrade``); every key of the
        current version is required except ``provenance`` and ``loads``."""
        d = upgrade(data)
        names = cls._fields()
        missing = [n for n in names if n not in d and n not in ("provenance", "loads")]
        unknown = sorted(set(d) - set(names) - set(cls._HEADER))
        if missing or unknown:
            raise SpecError(f"spec {d.get('name', '?')!r}: " + "; ".join(
                ([f"missing {missing}"] if missing else []) + ([f"unknown {unknown}"] if unknown else [])))
        return cls(**{n: d[n] for n in names if n in d})


def spec_dict(source) -> dict:
    """A spec as a plain version-2 dict: from a Spec, a dict of any version, or a spec.json path."""
    if isinstance(source, Spec):
        return source.to_dict()
    if isinstance(source, (str, Path)):
        source = json.loads(Path(source).read_text())
    return upgrade(source)


def load_spec(source) -> Spec:
    """A Spec from a spec.json path, a dict of any version, or a Spec (returned as is)."""
    return source if isinstance(source, Spec) else Spec.from_dict(spec_dict(source))
