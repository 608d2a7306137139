"""Build rosbags message objects with every field not given set to its ROS default
(zeros, empty strings and sequences), so converters name only the fields they fill.

The defaults of a type are built once per type store and shared by every message built
after: built messages are written and dropped, never modified in place.
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

_NUMPY = {
    "bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
    "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
    "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64,
}


def _default(store: Any, spec: tuple) -> Any:
    from rosbags.typesys.base import Nodetype

    kind, detail = spec
    if kind == Nodetype.NAME:
        return build(store, detail)
    if kind == Nodetype.BASE:
        name = detail[0]
        if name == "string":
            return ""
        if name == "bool":
            return False
        return 0.0 if name.startswith("float") else 0
    if kind == Nodetype.ARRAY:
        (sub_kind, sub), n = detail
        if sub_kind == Nodetype.BASE and sub[0] in _NUMPY:
            return np.zeros(n, dtype=_NUMPY[sub[0]])
        return [_default(store, (sub_kind, sub)) for _ in range(n)]
    if kind == Nodetype.SEQUENCE:
        (sub_kind, sub), _ = detail
        if sub_kind == Nodetype.BASE and sub[0] in _NUMPY:
            return np.zeros(0, dtype=_NUMPY[sub[0]])
        return []
    raise TypeError(f"unsupported field spec {spec!r}")


def build(store: Any, typename: str, **fields: Any) -> Any:
    """An instance of ``typename`` (``pkg/msg/Name``) from ``store``.

    Args:
        store: a rosbags ``Typestore`` holding ``typename``.
        typename: the ROS 2 type name.
        **fields: values of some fields; the others get their ROS defaults.

    Raises:
        KeyError: ``typename`` unknown to the store.
        TypeError: a field name the type does not have.
    """
    per_store = _DEFAULTS.get(store)
    if per_store is None:
        per_store = _DEFAULTS[store] = {}
    defaults = per_store.get(typename)
    if defaults is None:
        _, fdefs = store.fielddefs[typename]
        defaults = per_store[typename] = {n: _default(store, spec) for n, spec in fdefs}
    unknown = fields.keys() - defaults.keys()
    if unknown:
        raise TypeError(f"{typename} has no field(s) {sorted(unknown)}")
    return store.types[typename](**{**defaults, **fields})


#: type store -> type name -> field name -> default value (shared, read-only)
_DEFAULTS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
