"""Family entries merged onto a catalog's ``defaults`` (recording where every value was
written) and completed with the spec's defaults (listing required keys still missing)."""

from __future__ import annotations

import copy
from typing import Any

from rodcad.catalog.spec import OneOrMany
from rodcad.yamlio import MISSING, child_path
from rodcad.yamlspec import Nullable, Obj

__all__ = ["complete", "merge_defaults", "record"]


def merge_defaults(base: Any, over: Any, base_path: str, over_path: str, sources: dict[str, str], rel: str) -> Any:
    """Deep-merge ``over`` onto ``base`` (mappings key by key, anything else
    replaced), recording for every leaf which key path it came from."""
    if isinstance(base, dict) and isinstance(over, dict):
        out: dict[str, Any] = {}
        for key in list(base) + [k for k in over if k not in base]:
            r = child_path(rel, key)
            if key in over and key in base:
                out[key] = merge_defaults(base[key], over[key], child_path(base_path, key),
                                  child_path(over_path, key), sources, r)
            elif key in over:
                out[key] = record(over[key], child_path(over_path, key), sources, r)
            else:
                out[key] = record(base[key], child_path(base_path, key), sources, r)
        sources[rel] = over_path
        return out
    return record(over, over_path, sources, rel)


def record(value: Any, path: str, sources: dict[str, str], rel: str) -> Any:
    sources[rel] = path
    if isinstance(value, dict):
        for key, val in value.items():
            record(val, child_path(path, key), sources, child_path(rel, key))
    elif isinstance(value, list):
        for i, val in enumerate(value):
            record(val, child_path(path, i), sources, child_path(rel, i))
    return copy.deepcopy(value)


def complete(spec: Obj, value: dict[str, Any], rel: str, missing: list[str]) -> None:
    """Fill defaults into ``value`` and list required keys still missing."""
    for key, f in spec.fields.items():
        r = child_path(rel, key)
        if key not in value:
            if f.required:
                missing.append(r)
                continue
            if f.default is MISSING:
                continue
            value[key] = copy.deepcopy(f.default)
        sub = f.spec.inner if isinstance(f.spec, Nullable) else f.spec
        if isinstance(sub, OneOrMany):  # one mapping, or a list of them (every item complete)
            sub, items = sub.item, value.get(key)
            if isinstance(items, list):
                for i, item in enumerate(items):
                    if isinstance(item, dict):
                        complete(sub, item, child_path(r, i), missing)
                continue
        if isinstance(sub, Obj) and isinstance(value.get(key), dict):
            complete(sub, value[key], r, missing)
