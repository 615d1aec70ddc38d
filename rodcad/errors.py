"""One error type for bad user input, carrying every problem found, and one for requests
the physics or fabrication cannot meet.

Each problem is printed as ``FILE:LINE:COL: key.path: message`` (yamllint's
location format with cfgv's key path), all of them at once, and the CLI exits
with code 2 without a traceback. A :class:`DesignLimit` is not the file's mistake: one
line, exit 1.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Problem:
    """One thing wrong with an input file.

    Attributes:
        file: path of the file as the user named it.
        line: 1-based line number (0 when unknown).
        column: 1-based column number (0 when unknown).
        key: dotted key path such as ``families[2].lengths`` ('' for the file itself).
        message: what is wrong, in words a user can act on.
    """

    file: str
    line: int
    column: int
    key: str
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}" if self.line else f"{self.file}:0:0"
        key = f" {self.key}:" if self.key else ""
        return f"{where}:{key} {self.message}"


@dataclass
class InputError(Exception):
    """Bad input: a list of :class:`Problem`, reported together."""

    problems: list[Problem] = field(default_factory=list)

    def __str__(self) -> str:
        return "\n".join(str(p) for p in self.problems)


class DesignLimit(Exception):
    """A request the physics or fabrication cannot meet (not the input file's mistake): the
    CLI prints its message in one line and exits 1, leaving the outputs as they were."""
