"""Specs of a YAML document a person edits (:class:`Obj`, :class:`Num`, :class:`Str`, ...): each
checks a node, collects every problem with its position, and generates its JSON Schema.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import yaml

from rodcad.yamlio import (
    MISSING,
    TAG_BOOL,
    TAG_FLOAT,
    TAG_INT,
    TAG_MERGE,
    TAG_NULL,
    TAG_STR,
    Pos,
    Validator,
    child_path,
    format_number,
    freeze_value,
    show_value,
    suggest,
)

__all__ = ['MAX_MAGNITUDE', 'Spec', 'Any_', 'Str', 'Bool', 'Num', 'Nullable', 'ListOf', 'OneOrList', 'Field', 'CrossCheck', 'Obj', 'Checked', 'check_document']


def _kind(node: yaml.Node) -> str:
    """Describe what a node holds, for 'expected X, got Y' messages."""
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if isinstance(node, yaml.SequenceNode):
        return "a list"
    tag = node.tag
    if tag == TAG_NULL:
        return "nothing (null)"
    if tag == TAG_BOOL:
        return f"a boolean ({node.value})"
    if tag in (TAG_INT, TAG_FLOAT):
        return f"a number ({node.value})"
    return f"a string ({node.value!r})"


class Spec:
    """Base class: checks one YAML node and turns it into a Python value.

    Subclasses implement :meth:`check` (return the value, or MISSING after
    reporting a problem) and :meth:`json_schema`.

    Attributes:
        description: shown in the JSON Schema (editors display it).
    """

    description: str = ""

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        raise NotImplementedError

    def json_schema(self) -> dict[str, Any]:
        raise NotImplementedError

    def _describe(self, schema: dict[str, Any]) -> dict[str, Any]:
        if self.description:
            schema = {"description": self.description, **schema}
        return schema


class Any_(Spec):
    """Accepts any value (converted with PyYAML's safe constructor)."""

    def __init__(self, description: str = "") -> None:
        self.description = description

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        return yaml.SafeLoader("").construct_document(node)

    def json_schema(self) -> dict[str, Any]:
        return self._describe({})


class Str(Spec):
    """A string, optionally from a fixed set of choices or matching a pattern.

    Args:
        choices: allowed values (did-you-mean suggestions come from these).
        pattern: regular expression the whole string must match.
        pattern_hint: words describing the pattern for messages.
        max_length: longest string accepted (characters), or None.
        description: JSON Schema description.
    """

    def __init__(
        self,
        *,
        choices: Sequence[str] | None = None,
        pattern: str | None = None,
        pattern_hint: str = "",
        max_length: int | None = None,
        description: str = "",
    ) -> None:
        self.choices = tuple(choices) if choices else None
        self.pattern = pattern
        self.pattern_hint = pattern_hint
        self.max_length = max_length
        self.description = description

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if not isinstance(node, yaml.ScalarNode) or node.tag in (TAG_NULL,):
            v.report(node, path, f"expected a string, got {_kind(node)}")
            return MISSING
        if node.tag in (TAG_INT, TAG_FLOAT, TAG_BOOL):
            v.report(node, path, f"expected a string, got {_kind(node)}; quote it if you meant text")
            return MISSING
        text = node.value
        if self.max_length is not None and len(text) > self.max_length:
            v.report(node, path, f"{len(text)} characters long; keep it under {self.max_length + 1}")
            return MISSING
        if self.choices is not None and text not in self.choices:
            v.report(node, path, f"unknown value {text!r}{suggest(text, self.choices)}")
            return MISSING
        if self.pattern is not None and not re.fullmatch(self.pattern, text):
            hint = self.pattern_hint or f"matching {self.pattern}"
            v.report(node, path, f"{text!r} is not {hint}")
            return MISSING
        return text

    def json_schema(self) -> dict[str, Any]:
        schema: dict[str, Any] = {"type": "string"}
        if self.choices is not None:
            schema["enum"] = list(self.choices)
        if self.pattern is not None:
            schema["pattern"] = f"^(?:{self.pattern})$"
        if self.max_length is not None:
            schema["maxLength"] = self.max_length
        return self._describe(schema)


class Bool(Spec):
    """``true`` or ``false``."""

    def __init__(self, description: str = "") -> None:
        self.description = description

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.ScalarNode) and node.tag == TAG_BOOL:
            return node.value.lower() in ("true", "yes", "on", "y")
        v.report(node, path, f"expected true or false, got {_kind(node)}")
        return MISSING

    def json_schema(self) -> dict[str, Any]:
        return self._describe({"type": "boolean"})


#: No number a person writes in a design or catalog means anything beyond this (mm, g,
#: degrees, counts, seeds): larger ones are rejected before they overflow a computation.
MAX_MAGNITUDE = 1e12


class Num(Spec):
    """A finite number with optional bounds and a unit for messages.

    Args:
        minimum: smallest allowed value (inclusive).
        maximum: largest allowed value (inclusive).
        exclusive_minimum: the value must be greater than this.
        exclusive_maximum: the value must be less than this.
        integer: only whole numbers.
        unit: unit written after numbers in messages ("mm", "deg", ...).
        description: JSON Schema description.
    """

    def __init__(
        self,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        exclusive_minimum: float | None = None,
        exclusive_maximum: float | None = None,
        integer: bool = False,
        unit: str = "",
        description: str = "",
    ) -> None:
        self.minimum = minimum
        self.maximum = maximum
        self.exclusive_minimum = exclusive_minimum
        self.exclusive_maximum = exclusive_maximum
        self.integer = integer
        self.unit = unit
        self.description = description

    def _u(self, x: float) -> str:
        return f"{format_number(x)} {self.unit}" if self.unit else format_number(x)

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        value = _number(node)
        if value is None:
            want = "a whole number" if self.integer else "a number"
            v.report(node, path, f"expected {want}, got {_kind(node)}")
            return MISSING
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an integer too large for a float
            finite = True
        if not finite:
            v.report(node, path, f"expected a finite number, got {node.value}")
            return MISSING
        if abs(value) > MAX_MAGNITUDE:
            shown = node.value if len(str(node.value)) <= 24 else str(node.value)[:20] + "..."
            v.report(node, path, f"expected a number between {-MAX_MAGNITUDE:g} and {MAX_MAGNITUDE:g}, got {shown}")
            return MISSING
        if self.integer and not float(value).is_integer():
            v.report(node, path, f"expected a whole number, got {node.value}")
            return MISSING
        got = f" (got {format_number(value)})"
        lo_ok = (self.minimum is None or value >= self.minimum) and (
            self.exclusive_minimum is None or value > self.exclusive_minimum
        )
        hi_ok = (self.maximum is None or value <= self.maximum) and (
            self.exclusive_maximum is None or value < self.exclusive_maximum
        )
        if not (lo_ok and hi_ok):
            v.report(node, path, self._range_text() + got)
            return MISSING
        return int(value) if self.integer else float(value)

    def _range_text(self) -> str:
        lo = self.minimum if self.minimum is not None else self.exclusive_minimum
        hi = self.maximum if self.maximum is not None else self.exclusive_maximum
        lo_incl = self.minimum is not None
        hi_incl = self.maximum is not None
        if lo is not None and hi is not None:
            if lo_incl and hi_incl:
                return f"must be between {self._u(lo)} and {self._u(hi)}"
            left = "at least" if lo_incl else "greater than"
            right = "at most" if hi_incl else "less than"
            return f"must be {left} {self._u(lo)} and {right} {self._u(hi)}"
        if lo is not None:
            return f"must be {'at least' if lo_incl else 'greater than'} {self._u(lo)}"
        if hi is not None:
            return f"must be {'at most' if hi_incl else 'less than'} {self._u(hi)}"
        return "out of range"  # pragma: no cover - no bounds means never out of range

    def json_schema(self) -> dict[str, Any]:
        schema: dict[str, Any] = {"type": "integer" if self.integer else "number"}
        for key, val in (
            ("minimum", self.minimum),
            ("maximum", self.maximum),
            ("exclusiveMinimum", self.exclusive_minimum),
            ("exclusiveMaximum", self.exclusive_maximum),
        ):
            if val is not None:
                schema[key] = val
        description = self.description
        if self.unit and f"({self.unit})" not in description:
            description = f"{description} ({self.unit})".strip()
        if description:
            schema = {"description": description, **schema}
        return schema


def _number(node: yaml.Node) -> float | None:
    """The number a scalar node holds, or None.

    Plain (unquoted) scalars such as ``1e3`` that YAML 1.1 reads as strings are
    accepted as numbers, as a person would expect; quoted strings and booleans
    are not numbers.
    """
    if not isinstance(node, yaml.ScalarNode):
        return None
    text = node.value.strip()
    if node.tag == TAG_INT:
        try:
            return int(yaml.SafeLoader("").construct_yaml_int(node))
        except (ValueError, TypeError):  # pragma: no cover - resolver agreed it is an int
            return None
    if node.tag == TAG_FLOAT:
        return float(yaml.SafeLoader("").construct_yaml_float(node))
    if node.tag == TAG_STR and node.style is None:
        try:
            value = float(text)
        except ValueError:
            return None
        return value
    return None


class Nullable(Spec):
    """Either ``null`` (value None) or a value of the inner spec."""

    def __init__(self, inner: Spec, description: str = "") -> None:
        self.inner = inner
        self.description = description or inner.description

    def check(self, node: yaml.Node, path: str, v: Validator) -> Any:
        if isinstance(node, yaml.ScalarNode) and node.tag == TAG_NULL:
            return None
        return self.inner.check(node, path, v)

    def json_schema(self) -> dict[str, Any]:
        inner = dict(self.inner.json_schema())
        inner.pop("description", None)
        return self._describe({"anyOf": [inner, {"type": "null"}]})


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
            v.report(node, path, f"expected a list, got {_kind(node)}")
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
            v.report(node, path, f"expected a mapping, got {_kind(node)}")
            return MISSING
        out: dict[str, Any] = {}
        seen: dict[str, Pos] = {}
        for key_node, value_node in _flatten(node, path, v):
            if not isinstance(key_node, yaml.ScalarNode) or key_node.tag in (TAG_NULL,):
                v.report(key_node, path, f"keys must be plain names, got {_kind(key_node)}")
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
                    v.report(src, path, f"a merge key '<<' needs a mapping, got {_kind(src)}")
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
