"""The rod types of an earlier build, re-created from its catalog and design.json.

A fixed menu's rods are looked up by name; rods printed to order (a family with ranges,
:meth:`rodcad.catalog.model.Catalog.rod`) are made again from the family's template and
the ``params`` design.json gives them (length, curvature, both ends). Either way the
rod must be the one that was built: its parameters must equal design.json's.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import Catalog, EndShape, RodType, graduated
from rodcad.check.built import BuiltChain
from rodcad.errors import InputError
from rodcad.outputs.design_json import rod_params

__all__ = ["ChainTypes", "chain_types"]


@dataclass(frozen=True)
class ChainTypes:
    """The catalog and rods of a build.

    Attributes:
        catalog: the catalog (with the rods printed to order added).
        rods: the rod type per chain position.
        fabrication_seed: seed of the cavity layouts (the design file's, else 0).
        g: gravity (m/s^2) of the design (9.81 when the design file is gone).
        source: where the catalog came from, in words.
        target_curve: the design's dense target curve (None when the design file is gone).
    """

    catalog: Catalog
    rods: list[RodType]
    fabrication_seed: int
    g: float
    source: str
    target_curve: np.ndarray | None = None


def _close(a: object, b: object, rel: float = 1e-9) -> bool:
    """JSON values equal, numbers to ``rel``."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k], rel) for k in a)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return abs(float(a) - float(b)) <= rel * max(1.0, abs(float(a)), abs(float(b)))
    return a == b


def _from_design_file(built: BuiltChain) -> tuple[Catalog, int, float, str, np.ndarray | None] | None:
    """The catalog, fabrication seed and g from the design file named in design.json,
    if it is still there, still loads and names the same catalog."""
    from rodcad.design.loader import load_design

    name = built.data.get("design_file")
    if not isinstance(name, str) or not name:
        return None
    for path in (Path(name), built.outdir.parent / name):
        if path.is_file():
            try:
                design = load_design(path)
            except (InputError, OSError, ValueError):
                return None
            if design.catalog.name != built.catalog:
                return None
            return design.catalog, design.fabrication_seed, design.g, f"the design file {path}", design.target_curve
    return None


def _printed(catalog: Catalog, name: str, params: dict) -> RodType | None:
    """A rod printed to order made again from its design.json params (None: the family
    is not printed to order)."""
    try:
        fam = catalog.family(str(params.get("family")))
    except KeyError:
        return None
    if fam.template is None:
        return None
    t = fam.template
    ends = params.get("ends") or {}
    geom = dataclasses.replace(t.geometry, length=float(params["length"]), curvature=float(params["curvature"]),
                               first=EndShape(**{k: float(v) for k, v in ends["first"].items()}),
                               second=EndShape(**{k: float(v) for k, v in ends["second"].items()}))
    scale = float(params.get("scale", t.scale))
    if fam.ranges is not None and fam.ranges.scale is not None:  # a graduated rod: its body at its scale
        geom = graduated(geom, scale, t.material.min_wall)
    else:
        scale = t.scale
    return dataclasses.replace(t, name=name, length=geom.length, curvature=geom.curvature, geometry=geom, scale=scale)


def chain_types(built: BuiltChain) -> ChainTypes:
    """The catalog and the rod type of every position of a build.

    The catalog comes from the design file design.json names (when it is still there
    and names the same catalog), else from the shipped catalog of that name.

    Raises:
        InputError: the catalog cannot be found, or a rod is not what was built (the catalog
            changed since the build).
    """
    found = _from_design_file(built)
    if found is None:
        try:
            catalog = load_catalog(built.catalog)
        except InputError as err:
            raise InputError([built.problem("catalog", f"the catalog {built.catalog!r} the chain was built from "
                                            f"cannot be loaded ({'; '.join(p.message for p in err.problems)}); "
                                            "run `rodcad check` where `rodcad build` ran, with the design file "
                                            "in place")]) from None
        found = (catalog, 0, 9.81, f"the catalog {catalog.path}", None)
    catalog, seed, g, source, curve = found
    rods: list[RodType] = []
    problems = []
    for r in built.rods:
        key = f"rods[{r.index}]"
        if r.type in catalog:
            rod: RodType | None = catalog[r.type]
        else:
            try:
                rod = _printed(catalog, r.type, r.params)
            except (KeyError, TypeError, ValueError) as err:
                problems.append(built.problem(f"{key}.params", f"cannot make the rod again from its params ({err})"))
                continue
        if rod is None:
            problems.append(built.problem(f"{key}.type", f"{r.type!r} is not a rod of {source} (the catalog "
                                          "changed since the build?)"))
            continue
        if not _close(rod_params(rod), r.params):
            problems.append(built.problem(f"{key}.params", f"{r.type!r} in {source} is not the rod that was built "
                                          "(the catalog changed since the build?)"))
            continue
        rods.append(rod)
    if problems:
        raise InputError(problems)
    return ChainTypes(catalog.with_types([r for r in rods if r.name not in catalog]), rods, seed, g, source, curve)
