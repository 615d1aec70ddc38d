"""Reading a design file: validate it, resolve its catalog, build its target curve or
chandelier placements, and check constraints against the catalog (FILE:LINE:COL).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.catalog.loader import load_catalog
from rodcad.catalog.massrange import mass_info
from rodcad.design.model import (
    DESIGN_FORMAT,
    ChainRod,
    ChandelierSpec,
    Constraints,
    Design,
    FixedRod,
)
from rodcad.design.spec import FRAME_OF_PATTERN, PATTERNS, design_spec
from rodcad.errors import InputError, Problem
from rodcad.yamlio import load_yaml, load_yaml_text, suggest
from rodcad.yamlspec import check_document

__all__ = ['load_design']


def load_design(path: str | Path, *, text: str | None = None) -> Design:
    """Load and validate a design file, reporting every problem at once.

    Args:
        path: the design file (also the name used in problems when ``text`` is given).
        text: the file's content (for tests); read from ``path`` when None.

    Returns:
        The validated design with its catalog loaded and the target curve built.

    Raises:
        InputError: every problem as ``FILE:LINE:COL: key.path: message``.
    """
    path = Path(path)
    display = str(path)
    if text is None:
        if not path.is_file():
            raise InputError([Problem(display, 0, 0, "", "no such design file"
                                      if not path.is_dir() else "is a directory, expected a design file")])
        root = load_yaml(path, display)
    else:
        root = load_yaml_text(text, display)
    doc = check_document(root, design_spec(), filename=display, defer=True)
    v = doc.validator
    data: dict[str, Any] = doc.value if isinstance(doc.value, dict) else {}
    schema_ok = set(v.failed)

    def ok(key: str) -> bool:
        return v.ok(key, schema_ok) and key in data

    if "design" in data and data["design"] != DESIGN_FORMAT:
        v.report_at("design", f"unsupported design format {data['design']} (this rodcad reads format "
                    f"{DESIGN_FORMAT})")

    catalog = None
    if ok("catalog"):
        ref = data["catalog"]
        beside = path.parent / ref
        try:
            catalog = load_catalog(beside if beside.is_file() else ref)
        except InputError as err:
            for p in err.problems:
                if p.line == 0:  # the reference itself: point at the design's key
                    v.report_at("catalog", f"{ref!r}: {p.message} (looked next to the design file "
                                "and among the shipped catalogs)")
                else:  # problems inside the catalog file itself
                    v.problems.append(p)
                    v.failed.add("catalog")

    anchors = None
    if ok("anchors"):
        pts = data["anchors"]
        if len(pts) != 2 or any(len(p) != 2 for p in pts):
            v.report_at("anchors", "expected two anchors [[x, y], [x, y]]")
        else:
            anchors = np.asarray(pts, dtype=float)
            if np.hypot(*(anchors[1] - anchors[0])) <= 0:
                v.report_at("anchors", "the two anchors coincide")
                anchors = None

    net = None
    if "net" in data:  # a net takes its anchored nodes and target from the block
        for key in ("anchors", "target", "chain", "chandelier"):
            if key in data:
                v.report_at(key, f"a net design takes no {key!r}: its nodes, rods and anchored nodes are "
                            "in the 'net' block")
        if v.ok("net", schema_ok):
            from rodcad.design.net.target import net_target

            net = net_target(data["net"], v, path.parent)
        anchors = np.array([[0.0, 0.0], [1.0, 0.0]])  # unused for a net
    elif "anchors" not in data and "chandelier" not in data and v.ok("", schema_ok):
        v.report_at("", "missing required key 'anchors' (or describe a 'chandelier')")
    if "chandelier" in data:  # a chandelier's chains take their anchors and targets from the block
        for key, where in (("anchors", "its pattern"), ("target", "chandelier.target or each chain's target"),
                           ("chain", "its chains")):
            if key in data:
                v.report_at(key, f"a chandelier takes no top-level {key!r}: it comes from {where}")
    placements = chain_targets = None
    if "chandelier" in data and v.ok("chandelier", schema_ok):
        placements, chain_targets = _chandelier(data["chandelier"], v)
        if placements is not None:
            anchors = np.array([[0.0, 0.0], [1.0, 0.0]])  # unused for a chandelier
    if not any(k in data for k in ("target", "chain", "chandelier", "net")) and v.ok("", schema_ok):
        v.report_at("", "give a 'target' to design a chain for, an explicit 'chain' to simulate, or a 'net'")

    names = catalog.names if catalog is not None else None
    by_name = {t.name: t for t in catalog} if catalog is not None else {}

    def check_type(key: str, name: str) -> bool:
        if names is None:
            return False
        if name not in by_name:
            v.report_at(key, f"unknown rod type {name!r} in catalog {catalog.name!r}{suggest(name, names)}")
            return False
        return True

    # explicit chain: every item's type is checked, even when another item failed
    chain = None
    items = data.get("chain") if isinstance(data.get("chain"), list) else []
    rods: list[ChainRod] = []
    for i, rod in enumerate(items):
        key = f"chain[{i}]"
        if not isinstance(rod, dict) or "type" not in rod or not check_type(f"{key}.type", rod["type"]):
            continue
        if v.ok(key, schema_ok):
            t = by_name[rod["type"]]
            rods.append(ChainRod(t.name, float(rod.get("mass", mass_info(t).solid_mass))))
    if items and len(rods) == len(items) and v.ok("chain", schema_ok):
        chain = rods
        if anchors is not None:
            reach = sum(by_name[r.type].length for r in chain)
            span = float(np.hypot(*(anchors[1] - anchors[0])))
            if span > reach * (1 + 1e-12):
                v.report_at("anchors", f"the anchors are {span:.6g} mm apart but the chain is only "
                            f"{reach:.6g} mm long (pin to pin): move them closer or add rods")

    # constraints
    c = data.get("constraints", {}) if isinstance(data.get("constraints"), dict) else {}
    types = None
    if isinstance(c.get("types"), list):
        good = [isinstance(n, str) and check_type(f"constraints.types[{i}]", n) for i, n in enumerate(c["types"])]
        types = tuple(c["types"]) if all(good) else None
    lengths = (tuple(float(x) for x in c["lengths"]) if v.ok("constraints.lengths", schema_ok)
               and isinstance(c.get("lengths"), list) else None)
    if lengths is not None and catalog is not None and not catalog.printed_families:
        # (rods printed to order: the planner says that lengths do not apply)
        have = sorted({t.length for t in catalog})
        for i, x in enumerate(lengths):
            if not any(math.isclose(x, h, rel_tol=1e-9) for h in have):
                v.report_at(f"constraints.lengths[{i}]", f"no rod type of catalog {catalog.name!r} is "
                            f"{x:g} mm long (lengths: {', '.join(f'{h:g}' for h in have)})")
    fixed = []
    for i, f in enumerate(c.get("fixed", []) if isinstance(c.get("fixed"), list) else []):
        key = f"constraints.fixed[{i}]"
        if not (isinstance(f, dict) and "index" in f and "type" in f):
            continue
        if check_type(f"{key}.type", f["type"]):
            t = by_name[f["type"]]
            m = f.get("mass")
            if m is not None:
                lo, hi = mass_info(t).mass_range
                if not lo * (1 - 1e-9) <= m <= hi * (1 + 1e-9):
                    v.report_at(f"{key}.mass", f"{m:g} g is outside what type {t.name!r} can be made to "
                                f"weigh ({lo:.4g} to {hi:.4g} g)")
            fixed.append(FixedRod(int(f["index"]), t.name, None if m is None else float(m)))
    seen: dict[int, int] = {}
    for i, f in enumerate(fixed):
        if f.index in seen:
            v.report_at(f"constraints.fixed[{i}].index", f"rod {f.index} is already fixed by "
                        f"constraints.fixed[{seen[f.index]}]")
        seen[f.index] = i
    constraints = Constraints(types, lengths, int(c["rods"]) if "rods" in c else None,
                              c.get("preferred_length"), tuple(fixed), c.get("joints", "any"),
                              bool(c.get("same_shell", False)), c.get("anchor_stops"),
                              _anchor_limits(c.get("anchor_limits_deg"), v), c.get("fuse"),
                              bool(data.get("robust", True)))

    # target
    form, params, curve = None, {}, None
    if ok("target") and anchors is not None and net is None:
        form, params, curve = _target(data["target"], anchors, v)

    v.problems.sort(key=lambda p: (p.file != display, p.line, p.column))
    v.raise_if_any()
    assert catalog is not None and anchors is not None
    name = data["name"]
    fab = data.get("fabrication", {})
    return Design(
        path=path,
        name=name,
        description=data.get("description", ""),
        catalog=catalog,
        catalog_ref=data["catalog"],
        anchors=anchors,
        target_form=form,
        target_params=params,
        target_curve=curve,
        chain=chain,
        constraints=constraints,
        method=data.get("method", "refine"),
        seed=int(data.get("seed", 0)),
        tolerance=data.get("tolerance"),
        g=float(data.get("g", 9.81)),
        cad=bool(fab.get("cad", True)),
        fabrication_seed=int(fab.get("seed", 0)),
        source=doc,
        chandelier=_chandelier_spec(data.get("chandelier")),
        placements=placements,
        chain_targets=chain_targets,
        net=net,
    )


def _chandelier_spec(c: dict[str, Any] | None) -> ChandelierSpec | None:
    """The checked ``chandelier`` block as a typed spec."""
    if c is None:
        return None
    frame = dict(c.get("frame") or {})
    kind = frame.pop("kind", None) or FRAME_OF_PATTERN[c["pattern"]]
    params = {k: v for k, v in c.items() if k not in ("pattern", "chains", "target", "frame")}
    return ChandelierSpec(c["pattern"], params, kind, frame, c.get("vertices"),
                          {k: v for k, v in c.items() if k != "chains"})


def _chandelier(c: dict[str, Any], v: Any) -> tuple[list[Any] | None, list[dict[str, Any]] | None]:
    """Chain placements and per-chain targets of a chandelier, every problem reported."""
    from rodcad.design.chandelier import explicit, polygon_frame, ring, two_rings

    pattern = c["pattern"]
    required, optional = PATTERNS[pattern]
    bad = False
    for k in required:
        if k not in c:
            v.report_at("chandelier", f"a {pattern} chandelier needs {k!r}")
            bad = True
    known = set(required) | set(optional) | {"pattern", "target", "frame", "chains"}
    for k in c:
        if k not in known:
            v.report_at(f"chandelier.{k}", f"a {pattern} chandelier takes no {k!r} "
                        f"(it takes: {', '.join(required + optional)})")
            bad = True
    if bad:
        return None, None
    try:
        if pattern == "ring":
            placements = ring(int(c["count"]), c["radius"], c.get("height", 0.0),
                                start_deg=c.get("start_deg", 0.0), gap=c.get("gap", 20.0))
        elif pattern == "two-rings":
            placements = two_rings(int(c["count"]), c["r_top"], c["z_top"], c["r_bottom"], c["z_bottom"],
                                     twist_deg=c.get("twist_deg", 0.0), start_deg=c.get("start_deg", 0.0))
        elif pattern == "polygon":
            placements = polygon_frame(c["vertices"], gap=c.get("gap", 20.0))
        else:
            pairs = []
            for i, ch in enumerate(c["chains"]):
                if "anchors" not in ch or len(ch["anchors"]) != 2:
                    v.report_at(f"chandelier.chains[{i}]", "an explicit chain needs 'anchors': "
                                "[[x, y, z], [x, y, z]]", fallback="chandelier.chains")
                    bad = True
                else:
                    pairs.append(ch["anchors"])
            if bad:
                return None, None
            placements = explicit(pairs)
    except ValueError as err:
        v.report_at("chandelier", str(err))
        return None, None
    n = len(placements)
    per = c.get("chains")
    if per is not None and pattern != "explicit":
        for i, ch in enumerate(per):
            if "anchors" in ch:
                v.report_at(f"chandelier.chains[{i}].anchors", f"a {pattern} chandelier places its chains itself; "
                            "anchors per chain are for the explicit pattern")
                bad = True
        if bad:
            return None, None
    if per is not None and len(per) != n:
        v.report_at("chandelier.chains", f"{len(per)} entries for {n} chains (give one per chain)")
        return None, None
    targets = []
    for i, p in enumerate(placements):
        own = per[i].get("target") if per is not None else None
        t = own if own is not None else c.get("target")
        key = f"chandelier.chains[{i}].target" if own is not None else "chandelier.target"
        if t is None:
            v.report_at("chandelier", f"chain {p.name} has no target (give 'target' for every chain, or one "
                        "per chain under 'chains')")
            return None, None
        a2, b2 = p.plane_anchors()
        form, params, curve = _target(t, np.array([a2, b2]), v, key=key)
        if curve is None:
            return None, None
        targets.append({"form": form, **params})
    return placements, targets


def _anchor_limits(value: Any, v: Any) -> tuple[tuple[float, float] | None, tuple[float, float] | None]:
    """``constraints.anchor_limits_deg`` checked: two entries, each null or [lo, hi] with lo <= hi."""
    if not isinstance(value, list):
        return (None, None)
    key = "constraints.anchor_limits_deg"
    if len(value) != 2:
        v.report_at(key, f"expected 2 entries (the first rod's and the last rod's [lo, hi] or null), got {len(value)}")
        return (None, None)
    out: list[tuple[float, float] | None] = []
    for i, lim in enumerate(value):
        if not isinstance(lim, list):
            out.append(None)
            continue
        which = "first" if i == 0 else "last"
        if len(lim) != 2:
            v.report_at(f"{key}[{i}]", f"expected [lo, hi] (deg) for the {which} rod's angle, got {len(lim)} numbers")
            out.append(None)
        elif lim[0] > lim[1]:
            v.report_at(f"{key}[{i}]", f"lo {lim[0]:g} deg is above hi {lim[1]:g} deg: give [lo, hi] for the "
                        f"{which} rod's angle from +x")
            out.append(None)
        else:
            out.append((float(lim[0]), float(lim[1])))
    return (out[0], out[1])


def _target(t: dict[str, Any], anchors: np.ndarray, v: Any, *,
            key: str = "target") -> tuple[str | None, dict[str, Any], np.ndarray | None]:
    """Check the target's parameters against its form and build the curve.

    Args:
        t: the checked target mapping.
        anchors: (2, 2) anchors A and B in the target's plane.
        v: the validator collecting problems.
        key: key path of the target mapping (e.g. ``chandelier.chains[2].target``).
    """
    from rodcad.design.targets import TARGET_FORMS, make_target

    form = t["form"]
    _, required, optional = TARGET_FORMS[form]
    params = {k: val for k, val in t.items() if k != "form"}
    bad = False
    for k in params:
        if k not in required + optional:
            takes = ", ".join(required + optional) or "no parameters"
            v.report_at(f"{key}.{k}", f"a {form} target takes no {k!r} (it takes: {takes})")
            bad = True
    for k in required:
        if k not in params:
            v.report_at(key, f"a {form} target needs {k!r}", fallback=key)
            bad = True
    if bad:
        return None, {}, None
    if "sides" in params:
        params["sides"] = int(params["sides"])
    if "samples" in params:
        params["samples"] = int(params["samples"])
    try:
        curve = make_target(form, anchors[0], anchors[1], **params)
    except (ValueError, ArithmeticError, SyntaxError, TypeError) as err:
        at = f"{key}.{required[0]}" if required else key
        v.report_at(at, f"cannot make the {form} target: {err}", fallback=key)
        return None, {}, None
    if not np.all(np.isfinite(curve)):
        v.report_at(key, f"the {form} target has points that are not finite numbers")
        return None, {}, None
    return form, params, curve
