"""The compound specs of a YAML document: lists (:class:`ListOf`, :class:`OneOrList`), mappings
with known keys (:class:`Obj`, its :class:`Field` entries and cross-field checks) and a whole
document checked at once (:func:`check_document`, :class:`Checked`).
"""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import yaml

from rodcad.yamlio import MISSING, TAG_MERGE, TAG_NULL, Pos, Validator, child_path, freeze_value, show_value, suggest
from rodcad.yamlspec.scalars import Spec, node_kind

__all__ = ['ListOf', 'OneOrList', 'Field', 'CrossCheck', 'Obj', 'Checked', 'check_document']


class ListOf(Spec):
    """A list whose items all follow one spec.

    Items that fail their spec stay in the list as ``MISSING`` (so indices keep
    matching key paths); the problems are in the validator.

    Args:
        item: spec of every item.
        min_items: fewest items allowed.
        unique: items must differ from each other.
        description: JSON Schema description.
    """

    def __init__(self, item: Spec, *, min_items: int = 0, unique: bool = False, description: str = "") -> None:
        self.item = item
        self.min_items = min_items
        self.unique = unique
        self.description = description

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if not isinstance(node, yaml.SequenceNode):
            v.report(node, path, f"expected a list, got {node_kind(node)}")
            return MISSING
        return self._check_items(node, path, v)

    def _check_items(self, node: yaml.SequenceNode, path: str, v: Validator) -> Any:
        if len(node.value) < self.min_items:
            items = "item" if self.min_items == 1 else "items"
            v.report(node, path, f"expected at least {self.min_items} {items}, got {len(node.value)}")
            return MISSING
        out: list[Any] = []
        seen: dict[Any, int] = {}
        for i, item in enumerate(node.value):
            p = child_path(path, i)
            v.positions[p] = Pos.of(item)
            value = self.item.check(item, p, v)
            if value is not MISSING and self.unique:
                key = freeze_value(value)
                if key in seen:
                    v.report(item, p, f"duplicate value {show_value(value)} (also item {seen[key]})")
                    value = MISSING
                else:
                    seen[key] = i
            out.append(value)
        return out

    def json_schema(self) -> dict[str, Any]:
        schema: dict[str, Any] = {"type": "array", "items": self.item.json_schema()}
        if self.min_items:
            schema["minItems"] = self.min_items
        if self.unique:
            schema["uniqueItems"] = True
        return self._describe(schema)


class OneOrList(ListOf):
    """One value or a list of values; the Python value is always a list."""

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.SequenceNode):
            if not node.value:  # an empty list would silently mean nothing
                v.report(node, path, "expected a value or a list of at least 1 item, got an empty list")
                return MISSING
            return self._check_items(node, path, v)
        value = self.item.check(node, path, v)
        return MISSING if value is MISSING else [value]

    def json_schema(self) -> dict[str, Any]:
        item = dict(self.item.json_schema())
        description = item.pop("description", "")
        array: dict[str, Any] = {"type": "array", "items": item, "minItems": max(1, self.min_items)}
        if self.unique:
            array["uniqueItems"] = True
        schema: dict[str, Any] = {"anyOf": [item, array]}
        description = self.description or description
        if description:
            schema = {"description": description, **schema}
        return schema


@dataclass
class Field:
    """One key of an :class:`Obj`.

    Attributes:
        spec: how the value is checked.
        required: the key must be given.
        default: value used when the key is absent (MISSING: leave it absent).
        description: shown in the JSON Schema (falls back to the spec's).
    """

    spec: Spec
    required: bool = False
    default: Any = MISSING
    description: str = ""


#: A cross-field check: receives the checked mapping (complete: no key of it
#: failed), its key path and the validator; reports problems itself.
CrossCheck = Callable[[dict[str, Any], str, Validator], None]


class Obj(Spec):
    """A mapping with known keys.

    The value is a dict of the keys that checked cleanly (best effort: a bad
    value is left out and reported), so that later checks can still look at
    the rest of the document.

    Unknown keys are reported with a did-you-mean suggestion, missing required
    keys at the mapping's own position, duplicate keys at the second
    occurrence. YAML merge keys (``<<: *anchor``) are honoured.

    Args:
        fields: key -> :class:`Field`, in the order the schema lists them.
        checks: cross-field checks run when every key checked cleanly.
        title: JSON Schema title.
        description: JSON Schema description.
    """

    def __init__(
        self,
        fields: Mapping[str, Field],
        *,
        checks: Iterable[CrossCheck] = (),
        title: str = "",
        description: str = "",
    ) -> None:
        self.fields = dict(fields)
        self.checks = tuple(checks)
        self.title = title
        self.description = description

    def replace(self, *, drop: Iterable[str] = (), all_optional: bool = False, **kw: Any) -> Obj:
        """A copy without the keys in ``drop`` (and with no required keys if asked)."""
        fields = {
            k: (Field(f.spec, False, f.default, f.description) if all_optional else f)
            for k, f in self.fields.items()
            if k not in set(drop)
        }
        return Obj(fields, checks=kw.get("checks", self.checks), title=kw.get("title", self.title),
                   description=kw.get("description", self.description))

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if not isinstance(node, yaml.MappingNode):
            v.report(node, path, f"expected a mapping, got {node_kind(node)}")
            return MISSING
        out: dict[str, Any] = {}
        seen: dict[str, Pos] = {}
        for key_node, value_node in _flatten(node, path, v):
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag in (TAG_NULL,):
                v.report(key_node, path, f"keys must be plain names, got {node_kind(key_node)}")
                continue
            key = key_node.value
            p = child_path(path, key)
            if key in seen:
                first = seen[key]
                v.report(key_node, p, f"duplicate key {key!r} (first given at line {first.line})")
                continue
            seen[key] = Pos.of(key_node)
            spec_field = self.fields.get(key)
            if spec_field is None:
                v.report(key_node, p, f"unknown key {key!r}{suggest(key, list(self.fields))}")
                continue
            v.positions[p] = Pos.of(value_node)
            value = spec_field.spec.check(value_node, p, v)
            if value is not MISSING:
                out[key] = value
        for key, spec_field in self.fields.items():
            if key in seen:
                continue
            if spec_field.required:
                v.report(node, path, f"missing required key {key!r}")
            elif spec_field.default is not MISSING:
                out[key] = copy.deepcopy(spec_field.default)
        if v.ok(path):
            for check in self.checks:
                check(out, path, v)
        return out

    def json_schema(self) -> dict[str, Any]:
        props: dict[str, Any] = {}
        for key, f in self.fields.items():
            schema = dict(f.spec.json_schema())
            if f.description:
                schema["description"] = f.description
            if f.default is not MISSING and f.default is not None:
                schema["default"] = f.default
            props[key] = schema
        out: dict[str, Any] = {"type": "object"}
        if self.title:
            out["title"] = self.title
        if self.description:
            out["description"] = self.description
        out["properties"] = props
        out["additionalProperties"] = False
        required = [k for k, f in self.fields.items() if f.required]
        if required:
            out["required"] = required
        return out


def _flatten(node: yaml.MappingNode, path: str, v: Validator) -> list[tuple[yaml.Node, yaml.Node]]:
    """Key/value node pairs of a mapping with YAML merge keys (``<<``) applied.

    Keys written in the mapping win over merged ones, as in YAML's merge spec.
    """
    own: list[tuple[yaml.Node, yaml.Node]] = []
    merged: list[tuple[yaml.Node, yaml.Node]] = []
    for key_node, value_node in node.value:
        if key_node.tag == TAG_MERGE:
            sources = value_node.value if isinstance(value_node, yaml.SequenceNode) else [value_node]
            for src in sources:
                if isinstance(src, yaml.MappingNode):
                    merged.extend(_flatten(src, path, v))
                else:
                    v.report(src, path, f"a merge key '<<' needs a mapping, got {node_kind(src)}")
        else:
            own.append((key_node, value_node))
    own_keys = {k.value for k, _ in own if isinstance(k, yaml.ScalarNode)}
    result: list[tuple[yaml.Node, yaml.Node]] = []
    merged_seen: set[str] = set()
    for k, val in merged:
        key = k.value if isinstance(k, yaml.ScalarNode) else None
        if key in own_keys or key in merged_seen:
            continue
        merged_seen.add(key)
        result.append((k, val))
    return result + own


@dataclass
class Checked:
    """A document that passed its schema.

    Attributes:
        value: plain Python data (dicts, lists, str, float, int, bool, None).
        validator: the validator used; its ``positions`` map key paths to
            positions and it collects problems from later cross-field checks.
    """

    value: Any
    validator: Validator

    @property
    def filename(self) -> str:
        return self.validator.filename

    def pos(self, path: str) -> Pos:
        """Position of the value at key path ``path`` (0, 0 when unknown)."""
        return self.validator.positions.get(path, Pos())


def check_document(
    root: yaml.Node | None, spec: Spec, *, filename: str | None = None, defer: bool = False
) -> Checked:
    """Check a composed document against ``spec``; raise every problem at once.

    Args:
        root: the document's root node (from :func:`load_yaml`), None if empty.
        spec: the schema.
        filename: file name for problems; taken from the node's mark when None.
        defer: do not raise for schema problems yet: return the best-effort
            value so the caller can run its own checks on the parts that are
            fine, then call ``checked.validator.raise_if_any()``.

    Returns:
        The checked document (``value`` is MISSING when the root itself is bad).

    Raises:
        InputError: listing every problem found (an empty file always raises).
    """
    name = filename or (root.start_mark.name if root is not None else "<input>")
    v = Validator(name)
    if root is None:
        v.report(Pos(1, 1), "", "the file is empty")
        v.raise_if_any()
    v.positions[""] = Pos.of(root)
    value = spec.check(root, "", v)
    if not defer:
        v.raise_if_any()
    return Checked(value, v)
