"""The base spec and the scalar specs of a YAML document (:class:`Spec`, :class:`Str`,
:class:`Bool`, :class:`Num`, :class:`Nullable`, :class:`Any_`): each checks a node, collects
every problem with its position, and generates its JSON Schema.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import yaml

from rodcad.yamlio import MISSING, TAG_BOOL, TAG_FLOAT, TAG_INT, TAG_NULL, TAG_STR, Validator, format_number, suggest

__all__ = ['MAX_MAGNITUDE', 'Spec', 'Any_', 'Str', 'Bool', 'Num', 'Nullable', 'node_kind']


def node_kind(node: yaml.Node) -> str:
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
            v.report(node, path, f"expected a string, got {node_kind(node)}")
            return MISSING
        if node.tag in (TAG_INT, TAG_FLOAT, TAG_BOOL):
            v.report(node, path, f"expected a string, got {node_kind(node)}; quote it if you meant text")
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
        v.report(node, path, f"expected true or false, got {node_kind(node)}")
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
            v.report(node, path, f"expected {want}, got {node_kind(node)}")
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
