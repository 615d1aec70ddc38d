"""YAML input with a line and column for every value (the specs that check it are in
:mod:`rodcad.yamlspec`).

A file a person edits is read with :func:`load_yaml` (PyYAML's ``compose``, so
every node keeps its position), then checked against a tree of *specs*
(:class:`rodcad.yamlspec.Obj`, ``Num``, ``Str``, ...). Checking collects **every**
problem as a :class:`rodcad.errors.Problem` (``FILE:LINE:COL: key.path:
message``) instead of stopping at the first one, and returns plain Python values
together with a map from key path to position, so that cross-field checks done
later (by the catalog or design loaders) can point at the right line too.

The same spec tree generates a JSON Schema (:meth:`Spec.json_schema`) for editor
completion, so the published schema and the validator cannot drift apart.

Example:
    >>> from rodcad.yamlspec import Field, Num, Obj, check_document
    >>> spec = Obj({"length": Field(Num(exclusive_minimum=0, unit="mm"), required=True)})
    >>> doc = check_document(load_yaml_text("length: -3\\n", "x.yaml"), spec)
    Traceback (most recent call last):
    ...
    rodcad.errors.InputError: x.yaml:1:9: length: must be greater than 0 mm (got -3)

Key paths look like ``families[2].joint.knuckle_radius``: mapping keys joined
by dots, list indices in brackets.
"""

from __future__ import annotations

import difflib
import io
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from rodcad.errors import InputError, Problem

__all__ = [
    "MISSING",
    "TAG_BOOL",
    "TAG_FLOAT",
    "TAG_INT",
    "TAG_MERGE",
    "TAG_NULL",
    "TAG_STR",
    "child_path",
    "format_number",
    "freeze_value",
    "load_yaml",
    "load_yaml_text",
    "Pos",
    "show_value",
    "suggest",
    "Validator",
]


TAG_STR = "tag:yaml.org,2002:str"


TAG_INT = "tag:yaml.org,2002:int"


TAG_FLOAT = "tag:yaml.org,2002:float"


TAG_BOOL = "tag:yaml.org,2002:bool"


TAG_NULL = "tag:yaml.org,2002:null"


TAG_MERGE = "tag:yaml.org,2002:merge"


@dataclass(frozen=True)
class Pos:
    """A 1-based position in a file (0, 0 when unknown)."""

    line: int = 0
    column: int = 0

    @classmethod
    def of(cls, node: yaml.Node) -> Pos:
        """Position where ``node`` starts (PyYAML marks are 0-based)."""
        mark = node.start_mark
        return cls(mark.line + 1, mark.column + 1)


def child_path(parent: str, key: str | int) -> str:
    """Key path of a child: ``a.b`` + ``c`` -> ``a.b.c``; ``a`` + 2 -> ``a[2]``."""
    if isinstance(key, int):
        return f"{parent}[{key}]"
    return f"{parent}.{key}" if parent else key


def format_number(x: float) -> str:
    """Short human form of a number: 3 -> '3', 0.25 -> '0.25', 1/3 -> '0.333333'."""
    if isinstance(x, bool):
        return str(x).lower()
    if isinstance(x, int) or (isinstance(x, float) and x.is_integer() and abs(x) < 1e15):
        return str(int(x))
    return f"{x:.6g}"


def load_yaml_text(text: str, filename: str) -> yaml.Node | None:
    """Compose YAML text into a node tree (positions kept), or raise InputError.

    Args:
        text: the YAML document.
        filename: how to name the file in problems.

    Returns:
        The root node, or None for an empty document.

    Raises:
        InputError: on a syntax error or when the text holds several documents.
    """
    stream = io.StringIO(text)
    stream.name = filename  # PyYAML names marks after the stream
    try:
        nodes = list(yaml.compose_all(stream, Loader=yaml.SafeLoader))
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        line, col = (mark.line + 1, mark.column + 1) if mark else (0, 0)
        what = err.problem or str(err)
        if err.context:
            what = f"{err.context}, {what}"
        raise InputError([Problem(filename, line, col, "", f"YAML syntax error: {what}")]) from None
    except yaml.YAMLError as err:  # pragma: no cover - non-marked errors are rare
        raise InputError([Problem(filename, 0, 0, "", f"YAML error: {err}")]) from None
    except RecursionError:
        raise InputError([Problem(filename, 0, 0, "", f"YAML nests more than {MAX_DEPTH} levels deep")]) from None
    if len(nodes) > 1:
        pos = Pos.of(nodes[1])
        raise InputError(
            [Problem(filename, pos.line, pos.column, "", "expected one YAML document, found several")]
        )
    if nodes:
        _check_shape(nodes[0], filename)
    return nodes[0] if nodes else None


#: Deepest nesting of mappings and lists read from a file a person edits.
MAX_DEPTH = 64


def _check_shape(root: yaml.Node, filename: str) -> None:
    """Refuse node graphs that refer to themselves (an alias inside its own anchor) or nest
    deeper than :data:`MAX_DEPTH` (walked without recursion)."""
    stack: list[tuple[yaml.Node, int, frozenset[int]]] = [(root, 1, frozenset())]
    while stack:
        node, depth, above = stack.pop()
        if id(node) in above:
            pos = Pos.of(node)
            raise InputError([Problem(filename, pos.line, pos.column, "",
                                      "this value refers to itself (an alias inside its own anchor)")])
        if depth > MAX_DEPTH:
            pos = Pos.of(node)
            raise InputError([Problem(filename, pos.line, pos.column, "", f"YAML nests more than {MAX_DEPTH} "
                                      "levels deep")])
        if isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        elif isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        else:
            continue
        inner = above | {id(node)}
        stack.extend((c, depth + 1, inner) for c in children)


def load_yaml(path: str | Path, display_name: str | None = None) -> yaml.Node | None:
    """Read and compose a YAML file; see :func:`load_yaml_text`.

    Args:
        path: the file to read.
        display_name: name used in problems (defaults to ``str(path)``).

    Raises:
        InputError: the file cannot be read, is not UTF-8, or is not valid YAML.
    """
    name = display_name if display_name is not None else str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError([Problem(name, 0, 0, "", "no such file")]) from None
    except IsADirectoryError:
        raise InputError([Problem(name, 0, 0, "", "is a directory, expected a YAML file")]) from None
    except UnicodeDecodeError as err:
        raise InputError([Problem(name, 0, 0, "", f"not UTF-8 text ({err.reason})")]) from None
    except OSError as err:
        raise InputError([Problem(name, 0, 0, "", f"cannot read: {err.strerror}")]) from None
    return load_yaml_text(text, name)


@dataclass
class Validator:
    """Collects problems and value positions while a document is checked.

    Attributes:
        filename: file name used in every problem.
        problems: problems found so far, in document order.
        positions: key path -> position of the value written there.
        failed: key paths at which a problem was reported.
    """

    filename: str
    problems: list[Problem] = field(default_factory=list)
    positions: dict[str, Pos] = field(default_factory=dict)
    failed: set[str] = field(default_factory=set)

    def report(self, where: Pos | yaml.Node | None, key: str, message: str) -> None:
        """Record one problem at ``where`` for key path ``key``."""
        if isinstance(where, yaml.Node):
            where = Pos.of(where)
        where = where or Pos()
        self.problems.append(Problem(self.filename, where.line, where.column, key, message))
        self.failed.add(key)

    def report_at(self, key: str, message: str, fallback: str | None = None) -> None:
        """Record a problem at the position recorded for key path ``key``.

        Args:
            key: key path of the offending value.
            message: what is wrong.
            fallback: a key path whose position to use when ``key`` was never
                written (e.g. the enclosing mapping).
        """
        pos = self.positions.get(key)
        if pos is None and fallback is not None:
            pos = self.positions.get(fallback)
        self.report(pos, key, message)

    def ok(self, path: str, failed: set[str] | None = None) -> bool:
        """True when no problem was reported at ``path`` or below it.

        Args:
            path: a key path ('' for the whole document).
            failed: the set of failed paths to consult (default: all so far).
        """
        failed = self.failed if failed is None else failed
        if not path:
            return not failed
        return not any(k == path or k.startswith((path + ".", path + "[")) for k in failed)

    def raise_if_any(self) -> None:
        """Raise :class:`InputError` with every problem found, if any."""
        if self.problems:
            raise InputError(list(self.problems))


#: Sentinel for "no default".
MISSING: Any = object()


def suggest(word: str, options: Sequence[str]) -> str:
    """' (did you mean 'x'?)' or ' (expected one of: a, b)' for messages."""
    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    if close:
        return f" (did you mean {close[0]!r}?)"
    if not options:
        return ""
    return f" (expected one of: {', '.join(options)})"


def freeze_value(value: Any) -> Any:
    if isinstance(value, dict):
        return tuple(sorted((k, freeze_value(v)) for k, v in value.items()))
    if isinstance(value, list):
        return tuple(freeze_value(v) for v in value)
    return value


def show_value(value: Any) -> str:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return format_number(value)
    return repr(value)




