"""Reading a catalog: resolve a shipped name or a path, validate it, apply defaults and
expand each family into named rod types, with FILE:LINE:COL for every problem.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rodcad.catalog.cache import register_seed
from rodcad.catalog.pins import PinMenu, family_pin, menu_from_block
from rodcad.errors import InputError, Problem
from rodcad.yamlio import (
    Pos,
    Validator,
    format_number,
    load_yaml,
    suggest,
)
from rodcad.yamlspec import Checked, check_document

if TYPE_CHECKING:  # pragma: no cover
    pass
from rodcad.catalog.stock import DEFAULT_MODULUS
from rodcad.catalog.model import (
    CATALOG_FORMAT,
    Balls,
    Fill,
    Catalog,
    EndShape,
    Family,
    Hinge,
    Material,
    Origin,
    Printer,
    Ranges,
    graduated,
    max_curvature,
    RodGeometry,
    RodType,
)
from rodcad.catalog.checks import (
    check_curvature,
    check_length,
    check_printer,
    check_scales,
    check_section,
    check_stops,
)
from rodcad.catalog.merge import complete, merge_defaults
from rodcad.catalog.paths import default_catalog_dir, shipped_catalogs
from rodcad.catalog.spec import catalog_spec, family_spec

__all__ = ["catalog_from_text", "load_catalog", "resolve_catalog"]


def resolve_catalog(name_or_path: str | Path, base_dir: str | Path | None = None) -> Path:
    """Find a catalog file from a path or a shipped catalog's name.

    Args:
        name_or_path: a path to a YAML file, or a name such as ``pla-pinned``
            (looked up as ``<base_dir>/<name>.yaml``).
        base_dir: folder of named catalogs (default: :func:`default_catalog_dir`).

    Returns:
        The catalog file's path (as given when it exists).

    Raises:
        InputError: nothing found, with the names of the shipped catalogs.
    """
    folder = Path(base_dir) if base_dir is not None else default_catalog_dir()
    if not str(name_or_path).strip():
        raise InputError([Problem("<catalog>", 0, 0, "", "no catalog named: give a catalog file or one of "
                                  + ", ".join(shipped_catalogs(folder)))])
    path = Path(name_or_path)
    if path.is_file():
        return path
    text = str(name_or_path)
    if "/" not in text and "\\" not in text:
        stem = text[:-5] if text.endswith(".yaml") else text[:-4] if text.endswith(".yml") else text
        for suffix in (".yaml", ".yml"):
            candidate = folder / f"{stem}{suffix}"
            if candidate.is_file():
                return candidate
    names = shipped_catalogs(folder)
    hint = suggest(text, names).replace("expected one of", "shipped catalogs")
    if path.is_dir():
        raise InputError([Problem(text, 0, 0, "", "is a directory, expected a catalog file")])
    raise InputError([Problem(text, 0, 0, "", f"no such catalog file or shipped catalog{hint}")])


@lru_cache(maxsize=8)
def _expanded(path: Path, display: str, digest: str) -> Catalog:
    """The catalog file checked and expanded (``display``: its name in messages), kept for
    this process by its path as given, that name and ``digest``, the hash of its text (a
    changed file is another key): a catalog is immutable and its expansion (every family's
    cross-field checks) takes a few tenths of a second, so a process that loads one file
    again (a chandelier's chains, the Python API, the tests) gets the same object."""
    del digest
    doc = check_document(load_yaml(path, display), catalog_spec(), filename=display, defer=True)
    return _build(doc, path)


def load_catalog(name_or_path: str | Path, base_dir: str | Path | None = None) -> Catalog:
    """Load and validate a catalog.

    Everything is checked at once: unknown keys, wrong types, out-of-range
    values and parameters that make no solid (knuckle wider than the rod, wall
    thicker than half the section, ends that cut through the rod, ...).

    Args:
        name_or_path: a catalog file or a shipped catalog's name (see
            :func:`resolve_catalog`).
        base_dir: folder of named catalogs.

    Returns:
        The catalog, its families expanded into rod types.

    Raises:
        InputError: every problem as ``FILE:LINE:COL: key.path: message``.

    A ``<stem>.cache.json`` next to the file (precomputed limits and masses,
    ``rodcad catalog precompute``) is registered as a seed of the disk cache.
    """
    path = resolve_catalog(name_or_path, base_dir)
    display = str(name_or_path) if Path(name_or_path) == path else str(path)
    try:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:  # load_yaml reports it
        digest = ""
    catalog = _expanded(path, display, digest) if digest else _expanded.__wrapped__(path, display, digest)
    seed = path.with_name(f"{path.stem}.cache.json")
    if seed.is_file():
        register_seed(seed)
    return catalog


def catalog_from_text(text: str, filename: str = "<catalog>") -> Catalog:
    """Validate catalog YAML given as text (for tests and tools)."""
    from rodcad.yamlio import load_yaml_text

    doc = check_document(load_yaml_text(text, filename), catalog_spec(), filename=filename, defer=True)
    return _build(doc, None)


@dataclass
class _FamilyContext:
    """Reports problems about one family at the position each value came from."""

    v: Validator
    name: str
    index: int
    sources: dict[str, str]
    seen: set[tuple[str, str]] = field(default_factory=set)
    ball_keys: tuple[str, ...] = ()  # key of each ball kind: 'balls' or 'balls[i]'

    @property
    def path(self) -> str:
        return f"families[{self.index}]"

    def source(self, rel: str) -> str:
        while rel and rel not in self.sources:
            rel = rel.rsplit(".", 1)[0] if "." in rel else ""
        return self.sources.get(rel, self.path)

    def report(self, rel: str, message: str) -> None:
        key = self.source(rel) if rel else self.path
        if not (key == self.path or key.startswith((self.path + ".", self.path + "["))):
            message = f"{message} (in family {self.name!r})"
        if (key, message) in self.seen:
            return
        self.seen.add((key, message))
        self.v.report_at(key, message, fallback=self.path)

    def origin(self, rel: str = "") -> Origin:
        key = self.source(rel) if rel else self.path
        pos = self.v.positions.get(key, self.v.positions.get(self.path, Pos()))
        return Origin(self.v.filename, key, pos.line, pos.column)


def _build(doc: Checked, path: Path | None) -> Catalog:
    """Expand a schema-checked document into a catalog, running the cross-field
    checks on every family whose own keys (and the defaults) checked cleanly."""
    v = doc.validator
    schema_failed = set(v.failed)
    data = doc.value if isinstance(doc.value, dict) else {}
    if "catalog" in data and data["catalog"] != CATALOG_FORMAT:
        v.report_at("catalog", f"unsupported catalog format {data['catalog']} "
                    f"(this rodcad reads format {CATALOG_FORMAT})")
    full = family_spec()
    defaults = data.get("defaults", {})
    defaults_ok = v.ok("defaults", schema_failed)
    printer = None
    if "printer" in data and v.ok("printer", schema_failed):
        p = data["printer"]
        bv = p["build_volume"]
        if len(bv) != 3:
            v.report_at("printer.build_volume", f"expected 3 numbers (x, y, z), got {len(bv)}")
        else:
            printer = Printer(tuple(bv), p["nozzle"], p.get("name", ""),  # type: ignore[arg-type]
                              p.get("mesh_deflection"), p.get("mesh_angle"))

    types: list[RodType] = []
    families: list[Family] = []
    family_names: dict[str, int] = {}
    type_names: dict[str, str] = {}
    entries = data.get("families")
    for i, entry in enumerate(entries if isinstance(entries, list) else []):
        fpath = f"families[{i}]"
        if not isinstance(entry, dict) or "name" not in entry:
            continue
        sources: dict[str, str] = {}
        merged = merge_defaults(defaults, entry, "defaults", fpath, sources, "")
        ctx = _FamilyContext(v, entry["name"], i, sources)
        if entry["name"] in family_names:
            ctx.report("name", f"duplicate family name {entry['name']!r} "
                       f"(also families[{family_names[entry['name']]}])")
            continue
        family_names[entry["name"]] = i
        if not (defaults_ok and v.ok(fpath, schema_failed)):
            continue  # its schema problems are reported; cross-checks would add noise
        missing: list[str] = []
        complete(full, merged, "", missing)
        for key in missing:
            if "[" in key:  # an item of a list (one ball kind of several): point at the item
                item = key.rsplit(".", 1)[0]
                v.report_at(ctx.source(item), f"missing required key {key.rsplit('.', 1)[1]!r}", fallback=fpath)
                continue
            v.report_at(fpath, f"missing required key {key!r} (give it in the family or under 'defaults')")
        if missing:
            continue
        expanded = _expand(merged, ctx, printer)
        ranges, template = None, None
        if isinstance(expanded, tuple):
            family_types, ranges, template = expanded
        else:
            family_types = expanded
        for t in family_types:
            if t.name in type_names:
                v.report(Pos(t.origin.line, t.origin.column), t.origin.key,
                         f"rod type name {t.name!r} is also made by {type_names[t.name]}")
                continue
            type_names[t.name] = f"family {merged['name']!r}"
            types.append(t)
        families.append(Family(merged["name"], merged.get("description", ""),
                               tuple(t.name for t in family_types), ctx.origin(), ranges, template))
    settings: dict[str, Any] = {}
    if isinstance(data.get("print"), dict) and v.ok("print", schema_failed):
        settings = dict(data["print"])
        nozzle = printer.nozzle if printer is not None else None
        for key in ("layer_height", "first_layer_height"):
            if nozzle is not None and key in settings and settings[key] > 0.8 * nozzle:
                v.report_at(f"print.{key}", f"{format_number(settings[key])} mm is more than 0.8 of the printer's "
                            f"{format_number(nozzle)} mm nozzle: the layers would not bond")
    node = None
    if types and v.ok("node", schema_failed):
        from rodcad.catalog.net.node import node_hardware

        node = node_hardware(data.get("node") or {}, types[0], v)
    pins = None
    if types and v.ok("pins", schema_failed):
        pins = pin_menu(data.get("pins"), types[0], data, v)
    v.raise_if_any()
    return Catalog(data["name"], data.get("description", ""), path, tuple(types), tuple(families), printer,
                   settings, node, pins)


def friction_range(value, report, key: str) -> tuple[float, float]:
    """A friction written as a number or [lo, hi] (schema-checked: a list of numbers) as
    (lo, hi); problems (more than two numbers, lo > hi) go to ``report(key, message)``."""
    vals = [float(x) for x in value]
    if len(vals) > 2 or vals[0] > vals[-1]:
        report(key, f"expected a friction coefficient or [lo, hi] with lo <= hi, got {vals}")
        return (max(vals),) * 2
    return vals[0], vals[-1]


def pin_menu(block: dict | None, rod: RodType, data: dict, v: Validator) -> PinMenu | None:
    """The catalog's joint hardware (its ``pins:`` block, schema-checked, or the default menu)
    around the families' own pin (``rod``'s hinge and its family's ``joint.friction``);
    problems at ``pins.options[i].<key>``. None where an option is unsound."""
    hinge = rod.geometry.hinge
    fam = next((f for f in data.get("families", []) if isinstance(f, dict) and f.get("name") == rod.family), {})
    raw = {**(data.get("defaults") or {}).get("joint", {}), **(fam.get("joint") or {})}.get("friction", [0.2, 0.4])
    own = family_pin(hinge.pin_diameter, hinge.pin_clearance, raw if isinstance(raw, list) else [raw])
    ok = True
    for i, o in enumerate((block or {}).get("options", [])):
        at = f"pins.options[{i}]"
        friction_range(o["friction"], v.report_at, f"{at}.friction")
        friction_range(o.get("torque", [0.0]), v.report_at, f"{at}.torque")
        if o["kind"] != "pin" and "outer_diameter" not in o:
            v.report_at(at, f"a {o['kind']} needs its outer_diameter (the tongue's printed hole, mm)")
            ok = False
        elif o["kind"] != "pin" and o["outer_diameter"] <= o["pin_diameter"] + o["clearance"]:
            v.report_at(f"{at}.outer_diameter", f"{format_number(o['outer_diameter'])} mm is not wider than the "
                        f"pin and its play ({format_number(o['pin_diameter'] + o['clearance'])} mm)")
            ok = False
    names = [o["name"] for o in (block or {}).get("options", [])]
    for i, n in enumerate(names):
        if n in names[:i]:
            v.report_at(f"pins.options[{i}].name", f"joint hardware {n!r} is listed twice")
            ok = False
    return menu_from_block(block, own) if ok and v.ok("pins") else None


def _expand(f: dict[str, Any], ctx: _FamilyContext, printer: Printer | None
            ) -> list[RodType] | tuple[list[RodType], Ranges, RodType]:
    """The rod types of one complete family, after cross-field checks (for a family
    printed to order: its reference types, ranges and template)."""
    sec, jt, ends, mat = f["section"], f["joint"], f["ends"], f["material"]
    material = Material(mat.get("name", ""), mat["density"], mat["min_wall"], mat.get("modulus", DEFAULT_MODULUS))
    friction = friction_range(jt["friction"], ctx.report, "joint.friction")[1]
    raw = f.get("balls")
    listed = isinstance(raw, list)
    kinds = tuple(Balls(b["diameter"], b["density"], b.get("clearance", 0.2), b.get("name", ""))
                  for b in (raw if listed else [raw] if raw is not None else []))
    ctx.ball_keys = tuple(f"balls[{i}]" if listed else "balls" for i in range(len(kinds)))

    def end(which: str) -> EndShape:
        over = ends.get(which, {})
        return EndShape(
            over.get("setback", ends["setback"]),
            over.get("top_chamfer", ends["top_chamfer"]),
            over.get("bottom_chamfer", ends["bottom_chamfer"]),
        )

    def end_key(which: str, key: str) -> str:
        return f"ends.{which}.{key}" if key in ends.get(which, {}) else f"ends.{key}"

    first, second = end("first"), end("second")
    w = material.min_wall
    if printer is not None and w < printer.nozzle:
        ctx.report("material.min_wall", f"minimum wall {format_number(w)} mm is thinner than the "
                   f"printer's nozzle ({format_number(printer.nozzle)} mm)")
    if isinstance(f["length"], dict) or isinstance(f["curvature"], dict) or "stops" in f or isinstance(f["scale"], dict):
        return _with_fill(f, ctx, material, _expand_ranges(f, ctx, printer, material, kinds, first, second, end_key))
    if f.get("fill") is not None:
        ctx.report("fill", "a fill is for rods printed to order: give the length as a range {min, max}")
        return []
    multi_scale = len(f["scale"]) > 1
    multi_curv = len(f["curvature"]) > 1
    out: list[RodType] = []
    ok = True
    per_scale: dict[int, tuple[float, float, Hinge, str]] = {}
    for si, scale in enumerate(f["scale"]):
        h, t = sec["height"] * scale, sec["thickness"] * scale
        hinge = Hinge(jt["layout"], jt["pin_diameter"], jt["pin_clearance"], jt["knuckle_radius"] * scale,
                      jt["tongue_thickness"] * scale, jt["layer_gap"], jt["radial_gap"])
        at = f" at scale {format_number(scale)}" if scale != 1 else ""
        ok &= check_section(ctx, h, t, hinge, material, kinds, first, second, end_key, at)
        per_scale[si] = (h, t, hinge, at)
    for li, length in enumerate(f["length"]):
        l_rel = f"length[{li}]" if len(f["length"]) > 1 else "length"
        for si, scale in enumerate(f["scale"]):
            h, t, hinge, at = per_scale[si]
            ok &= check_length(ctx, l_rel, length, h, hinge, material, first, second, end_key, at)
            for ci, curv in enumerate(f["curvature"]):
                c_rel = f"curvature[{ci}]" if multi_curv else "curvature"
                ok &= check_curvature(ctx, c_rel, curv, length, h)
                geom = RodGeometry(length, h, t, curv, hinge, first, second)
                if printer is not None:
                    ok &= check_printer(ctx, l_rel, geom, printer)
                name = f"{f['name']}-{format_number(length)}"
                if multi_scale:
                    name += f"-s{format_number(scale)}"
                if multi_curv:
                    name += f"-k{format_number(curv)}"
                out.append(RodType(name, f["name"], length, scale, curv, geom, material, kinds[0] if kinds else None,
                                   ctx.origin(l_rel), heavier=kinds[1:], friction=friction))
    return out if ok else []


def _range(ctx: _FamilyContext, f: dict[str, Any], key: str) -> tuple[float, float] | None:
    """A {min, max} value as a pair, or None (reported) when it is empty or inverted."""
    lo, hi = f[key]["min"], f[key]["max"]
    if not lo < hi:
        what = "empty" if lo == hi else "inverted"
        ctx.report(f"{key}.max", f"{what} range: max {format_number(hi)} must be above min {format_number(lo)}"
                   + (" (a single value is written without min and max)" if lo == hi else ""))
        return None
    return float(lo), float(hi)


def _with_fill(f: dict[str, Any], ctx: _FamilyContext, material: Material,
               expanded: list[RodType] | tuple[list[RodType], Ranges, RodType]
               ) -> list[RodType] | tuple[list[RodType], Ranges, RodType]:
    """A family printed to order with its ``fill`` (checked: the longest straight rod holds a
    chamber) on every rod."""
    if f.get("fill") is None or not isinstance(expanded, tuple):
        return expanded
    from rodcad.catalog.chamber import MAX_BRIDGE, chamber_model

    fl = f["fill"]
    fill = Fill(fl["name"], float(fl["density"]), float(fl.get("packing", 0.6)))
    refs, ranges, _ = expanded
    refs = [dataclasses.replace(r, fill=fill) for r in refs]
    longest = refs[-1]
    if chamber_model(longest.geometry, material.min_wall).max_volume <= 0:
        g = longest.geometry
        ctx.report("fill", f"no chamber fits in a {format_number(g.length)} mm rod of section "
                   f"{format_number(g.height)} x {format_number(g.thickness)} mm with the minimum wall of "
                   f"{format_number(material.min_wall)} mm around it (cells up to {format_number(MAX_BRIDGE)} mm "
                   "wide, clear of the hinges): a larger section, longer rods or a thinner wall")
        return []
    return refs, ranges, refs[0]


def _expand_ranges(f: dict[str, Any], ctx: _FamilyContext, printer: Printer | None, material: Material,
                   kinds: tuple[Balls, ...], first: EndShape, second: EndShape, end_key: Any
                   ) -> list[RodType] | tuple[list[RodType], Ranges, RodType]:
    """A family printed to order: ranges checked at their ends (every rod the design may
    make must be buildable), two reference types (shortest and longest, straight)."""
    fmt = format_number
    if not isinstance(f["length"], dict):
        for key in ("curvature", "stops", "scale"):
            if isinstance(f.get(key), dict):
                ctx.report(key, f"a {key} range is for rods printed to order: give the length as a range "
                           "{min, max} too")
        return []
    scales: tuple[float, float] | None = None
    if isinstance(f["scale"], dict):
        scales = _range(ctx, f, "scale")
        if scales is None:
            return []
        if f.get("fill") is not None:
            ctx.report("scale", "graduated rods (a scale range) take balls, not a fill: give one scale")
            return []
    elif len(f["scale"]) > 1:
        ctx.report("scale", "a family printed to order has one scale or a range {min, max} (graduated rods), "
                   "not a list")
        return []
    length = _range(ctx, f, "length")
    curv: tuple[float, float] | None
    if isinstance(f["curvature"], dict):
        curv = _range(ctx, f, "curvature")
    elif len(f["curvature"]) == 1:
        curv = (float(f["curvature"][0]),) * 2
    else:
        ctx.report("curvature", "a family printed to order takes one curvature or a range {min, max}, not a list")
        return []
    stops = None
    if "stops" in f:
        stops = _range(ctx, f, "stops")
        if stops is None:
            return []
    if length is None or curv is None:
        return []
    sec, jt = f["section"], f["joint"]
    friction = friction_range(jt["friction"], ctx.report, "joint.friction")[1]
    scale = 1.0 if scales is not None else f["scale"][0]
    h, t = sec["height"] * scale, sec["thickness"] * scale
    hinge = Hinge(jt["layout"], jt["pin_diameter"], jt["pin_clearance"], jt["knuckle_radius"] * scale,
                  jt["tongue_thickness"] * scale, jt["layer_gap"], jt["radial_gap"])
    if not check_section(ctx, h, t, hinge, material, kinds, first, second, end_key, ""):
        return []
    ok = True
    for rel, lv in (("length.min", length[0]), ("length.max", length[1])):
        ok &= check_length(ctx, rel, lv, h, hinge, material, first, second, end_key, "")
    k_big = max(abs(curv[0]), abs(curv[1]))
    k_rel = "curvature.max" if abs(curv[1]) >= abs(curv[0]) else "curvature.min"
    if ok and k_big:  # the shortest rod takes the whole range; longer ones at most a 120 deg arc
        ok &= check_curvature(ctx, k_rel, math.copysign(k_big, curv[1] if k_rel.endswith("max") else curv[0]),
                               length[0], h)
    if ok and printer is not None:
        k_sig = curv[1] if abs(curv[1]) >= abs(curv[0]) else curv[0]
        k_sig = math.copysign(min(abs(k_sig), max_curvature(length[1])), k_sig)
        ok &= check_printer(ctx, "length.max", RodGeometry(length[1], h, t, 0.0, hinge, first, second), printer)
        if ok and k_big:  # straight it fits: does its most curved form?
            ok &= check_printer(ctx, k_rel, RodGeometry(length[1], h, t, k_sig, hinge, first, second), printer)
    if ok and stops is not None:
        ok = check_stops(ctx, stops, length, curv, h, t, hinge, material, first, second)
    if ok and scales is not None:
        ok = check_scales(ctx, scales, length, stops, RodGeometry(length[1], h, t, 0.0, hinge, first, second),
                           material, printer)
    if not ok:
        return []
    k0 = min(max(0.0, curv[0]), curv[1])
    origin = ctx.origin("length")
    template = RodType(f"{f['name']}-{fmt(length[0])}", f["name"], length[0], scale, k0,
                       RodGeometry(length[0], h, t, k0, hinge, first, second), material, kinds[0] if kinds else None,
                       origin, heavier=kinds[1:], friction=friction)
    s_ref = 1.0 if scales is None else min(max(1.0, scales[0]), scales[1])
    refs = []
    for lv in length:
        g = graduated(RodGeometry(lv, h, t, k0, hinge, first, second), s_ref, material.min_wall)
        name = f"{f['name']}-{fmt(lv)}" + (f"-s{fmt(s_ref)}" if s_ref != 1.0 else "")
        refs.append(RodType(name, f["name"], lv, s_ref if scales is not None else scale, k0, g, material,
                            kinds[0] if kinds else None, origin, heavier=kinds[1:], friction=friction))
    res = f["length"].get("resolution")
    if res is not None and math.floor(length[1] / res + 1e-9) * res < length[0] - 1e-9:
        ctx.report("length.resolution", f"no multiple of {fmt(res)} mm lies between {fmt(length[0])} and "
                   f"{fmt(length[1])} mm")
        return []
    return refs, Ranges(length, curv, stops, None if res is None else float(res), scales), template
