"""``rodcad schema design|catalog [-o FILE]``: the JSON Schema of design or catalog files.

Editors (VS Code's YAML extension, for instance) complete and check files with
it; the published copies are examples/design.schema.json and
catalogs/catalog.schema.json.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["register", "run", "schema_text"]


def schema_text(kind: str) -> str:
    """The JSON Schema of ``kind`` ('design' or 'catalog') as indented JSON text."""
    if kind == "design":
        from rodcad.design.spec import design_schema

        schema = design_schema()
    else:
        from rodcad.catalog.spec import catalog_schema

        schema = catalog_schema()
    return json.dumps(schema, indent=2) + "\n"


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("schema", help="print the JSON Schema of design or catalog files",
                       description="Print (or write) the JSON Schema of design or catalog files.")
    p.add_argument("kind", choices=("design", "catalog"), help="which file format")
    p.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    text = schema_text(args.kind)
    if args.output:
        Path(args.output).write_text(text, encoding="utf-8")
    else:
        print(text, end="")
    return 0
