"""``rodcad catalog``: check, export and describe rod catalogs.

* ``rodcad catalog check CATALOG [--json]`` validates a catalog and prints, per
  rod type, its length, joint limits, solid mass, mass range and centre of mass,
  then the limits of every ordered pair of types that can be joined.
* ``rodcad catalog export CATALOG -o DIR`` writes ``DIR/<type>.step`` per type.
* ``rodcad catalog schema [-o FILE]`` prints (or writes) the JSON Schema of
  catalog files.
* ``rodcad catalog precompute CATALOG [-o FILE] [--jobs N]`` computes the
  joint limits, mass ranges and achievable mass intervals (fabrication seed 0)
  of every type into a seed file of the disk cache (default
  ``<catalog>.cache.json`` next to the catalog), read by every later run.

CATALOG is a path or the name of a shipped catalog (e.g. ``pla-pinned``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rodcad.catalog.cache import DiskCache
from rodcad.catalog.jointlimits import joint_limits
from rodcad.catalog.limits import TOLERANCE_DEG
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.model import Catalog
from rodcad.catalog.spec import catalog_schema
from rodcad.commands.group import command_group
from rodcad.errors import InputError, Problem
from rodcad.outputs.design_json import ball_text
from rodcad.outdir import write_atomic

__all__ = ["SEED_KINDS", "check_report", "precompute", "register", "schema_text"]


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``catalog`` command and its subcommands."""
    sub = command_group(subparsers, "catalog", help="check, export and describe rod catalogs",
                        description="Check, export and describe rod catalogs (YAML files of rod families).",
                        dest="catalog_command")

    check = sub.add_parser(
        "check",
        help="validate a catalog; print limits, masses and mass ranges per rod type",
        description="Validate a catalog and print, per rod type, its length, joint limits, solid mass, "
        "mass range and centre of mass, and the joint limits of every ordered pair of types. "
        "Results derived from the solids are cached on disk ($RODCAD_CACHE_DIR, default "
        "~/.cache/rodcad).",
    )
    check.add_argument("catalog", metavar="CATALOG", help="catalog file, or name of a shipped catalog")
    check.add_argument("--json", action="store_true", help="print JSON instead of tables")
    _common(check)
    check.set_defaults(handler=_check)

    export = sub.add_parser(
        "export",
        help="write one STEP file per rod type",
        description="Write DIR/<type>.step for every rod type of the catalog, in the rod frame: first "
        "hinge axis through the origin, second through (length, 0, 0), axes along +z (mm).",
    )
    export.add_argument("catalog", metavar="CATALOG", help="catalog file, or name of a shipped catalog")
    export.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder")
    export.set_defaults(handler=_export)

    pre = sub.add_parser(
        "precompute",
        help="precompute limits and mass tables into a seed file shipped with the catalog",
        description="Compute, from the solids and ignoring every cache, the joint limits of every ordered "
        "pair of types, each type's mass range and its achievable mass intervals (fabrication seed 0), "
        "and write them as a seed file of the disk cache: later runs read them instead of computing.",
    )
    pre.add_argument("catalog", metavar="CATALOG", help="catalog file, or name of a shipped catalog")
    pre.add_argument("-o", "--output", metavar="FILE",
                     help="seed file to write (default: <catalog stem>.cache.json next to the catalog)")
    pre.add_argument("--jobs", type=int, default=None, metavar="N",
                     help="worker processes (default: number of CPUs)")
    pre.set_defaults(handler=_precompute)

    schema = sub.add_parser(
        "schema",
        help="print the JSON Schema of catalog files",
        description="Print the JSON Schema of catalog files (generated from the validator).",
    )
    schema.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of stdout")
    schema.set_defaults(handler=_schema)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="worker processes for uncached computations (default: number of CPUs)")
    p.add_argument("--no-cache", action="store_true", help="recompute everything, do not use the disk cache")


# --------------------------------------------------------------------------- check


def check_report(catalog: Catalog, *, jobs: int | None = None, cache: DiskCache | None = None,
                 progress: bool = False) -> dict[str, Any]:
    """Everything ``catalog check --json`` prints, as a dict.

    Args:
        catalog: a loaded catalog.
        jobs: worker processes for uncached work.
        cache: disk cache (default location when None).
        progress: report progress on stderr.

    Returns:
        ``{"catalog", "file", "units", "types": [...], "pairs": [...],
        "problems": [...]}``; pairs that cannot be assembled (the rods
        interfere at every angle) are listed under "problems", not "pairs".

    Raises:
        InputError: a rod type's parameters make no valid solid.
    """
    t0 = time.perf_counter()
    masses, limits = _compute_tables(catalog, jobs=jobs, cache=cache, progress=progress)
    types = []
    for t in catalog.types:
        m = masses[t.name]
        entry: dict[str, Any] = {
            "name": t.name,
            "family": t.family,
            "length": t.length,
            "scale": t.scale,
            "curvature": t.curvature,
            "volume": round(m.volume, 3),
            "solid_mass": round(m.solid_mass, 4),
            "mass_range": [round(m.m_min, 4), round(m.m_max, 4)],
            "com": [round(m.com[0], 4), round(m.com[1], 4)],
            "cavities": {"radius": round(m.cavity_radius, 4), "count": m.cavity_count},
            "balls": (_balls_json(t, m) if t.balls is not None and t.fill is None else None),
            "fill": ({"name": t.fill.name, "max_g": round(m.m_max - m.m_min, 4),
                      "lightest": "the largest chamber, empty", "heaviest": "the largest chamber, filled"}
                     if t.fill is not None else None),
        }
        self_pair = limits.get((t.name, t.name))
        entry["self_limits_deg"] = _limits_json(self_pair) if self_pair and self_pair.assemblable else None
        types.append(entry)
    pairs = []
    problems = []
    for (left, right), r in limits.items():
        if r.assemblable:
            pairs.append({"left": left, "right": right, "limits_deg": _limits_json(r)})
        else:
            problems.append(str(catalog[right].origin.problem(
                f"rod types {left!r} and {right!r} interfere at every angle: they cannot be joined (their ends "
                "overlap whatever the bend; shorten the chamfers or add setback)")))
    computed = sum(1 for r in limits.values() if not r.cached)
    extended, sampled = _sampled_limits(catalog, jobs=jobs, cache=cache, progress=progress)
    lookup = _lookup_deviation(extended, {**limits, **sampled})
    lookup["sampled_printed_pairs"] = len(sampled)
    return {
        "catalog": catalog.name,
        "file": str(catalog.path) if catalog.path else None,
        "units": {"length": "mm", "mass": "g", "angle": "deg", "volume": "mm^3"},
        "families": [_family_json(f, catalog) for f in catalog.families],
        "types": types,
        "pairs": pairs,
        "problems": problems,
        "stats": {"pairs_computed": computed, "pairs_cached": len(limits) - computed,
                  "seconds": round(time.perf_counter() - t0, 3)},
        "limit_lookup": lookup,
    }


def _balls_json(t: Any, m: Any) -> dict[str, Any]:
    """The balls behind a type's heaviest mass (count, diameter, mass each, kind) and, per
    ball kind the catalog lists, how many fit and the heaviest mass they give."""
    heavy = t.ball_kinds[m.ball_kind]
    kinds = [{"kind": b.name or None, "diameter": b.diameter, "density": b.density, "mass_each": round(b.mass, 4),
              "count": n, "m_max": round(mk, 4)}
             for b, (n, mk) in zip(t.ball_kinds, m.kind_max or [(m.ball_count, m.m_max)])]
    return {"count": m.ball_count, "diameter": heavy.diameter, "mass_each": round(heavy.mass, 4),
            "kind": heavy.name or None, "kinds": kinds}


def _family_json(f: Any, catalog: Catalog) -> dict[str, Any]:
    """A family's parameters: ranges for rods printed to order, else its fixed menu."""
    if f.ranges is not None:
        r = f.ranges
        fill = f.template.fill if f.template is not None else None
        return {"name": f.name, "printed_to_order": True, "length": list(r.length),
                "curvature": list(r.curvature), "stops_deg": list(r.stops) if r.stops else None,
                "scale": list(r.scale) if r.scale else None, "mass_span": _mass_span_json(f, catalog),
                "fill": None if fill is None else {"name": fill.name, "density": fill.density,
                                                   "packing": fill.packing},
                "balls": _kinds_json(f.template), "types": list(f.type_names)}
    ts = [catalog[n] for n in f.type_names]
    return {"name": f.name, "printed_to_order": False, "length": sorted({t.length for t in ts}),
            "curvature": sorted({t.curvature for t in ts}), "stops_deg": None, "balls": _kinds_json(ts[0]),
            "types": list(f.type_names)}


def _mass_span_json(f: Any, catalog: Catalog) -> list[dict[str, Any]] | None:
    """A graduated family's mass span per table length: the lightest rod (its lowest scale,
    most cavities) to the heaviest (the highest scale that length takes, most balls), straight
    rods with the family's ends (from the family's mass table and the closed-form solids)."""
    from rodcad.catalog.printed import mass_table, table_lengths
    from rodcad.catalog.scaling import mass_span

    if f.ranges is None or f.ranges.scale is None:
        return None
    table = mass_table(f)
    out = []
    for length in table_lengths(f):
        lo, hi = mass_span(catalog, f.name, table, length)
        s_lo, s_hi = catalog.scale_range(f.name, length)
        out.append({"length": length, "scales": [round(s_lo, 4), round(s_hi, 4)], "mass": [round(lo, 4), round(hi, 4)],
                    "ratio": round(hi / lo, 3)})
    return out


def _kinds_json(t: Any) -> list[dict[str, Any]]:
    """The ball kinds a family's rods may hold, in the catalog's order of preference."""
    if t is None or t.fill is not None:
        return []
    return [{"kind": b.name or None, "diameter": b.diameter, "density": b.density} for b in t.ball_kinds]


def _family_lines(families: list[dict[str, Any]]) -> list[str]:
    printed = [f for f in families if f["printed_to_order"]]
    if not printed:
        return []
    lines = ["families printed to order (the design chooses every rod's own values within these ranges):"]
    for f in printed:
        lo, hi = f["length"]
        k0, k1 = f["curvature"]
        text = f"  {f['name']}: length {lo:g} to {hi:g} mm"
        text += f", curvature {k0:g} to {k1:g} /mm" if k0 != k1 else (f", curvature {k0:g} /mm" if k0 else ", straight")
        if f["stops_deg"]:
            text += f", stops printed at any bend from {f['stops_deg'][0]:g} to {f['stops_deg'][1]:g} deg"
        else:
            text += ", no stops printed to order"
        if f.get("scale"):
            text += (f", body scale {f['scale'][0]:g} to {f['scale'][1]:g} (graduated: the hinge ends stay the "
                     "family's)")
        if f.get("fill"):
            text += (f"; masses from one chamber per rod, empty or filled with {f['fill']['name']} "
                     f"({f['fill']['density']:g} g/cm^3 at {f['fill']['packing']:g} packing)")
        if len(f.get("balls") or []) > 1:
            text += "; balls: " + ", then ".join(f"{ball_text(b['diameter'], b['kind'] or '')} ({b['density']:g} g/cm^3)"
                                                 for b in f["balls"])
        lines.append(text + f" (reference types {', '.join(f['types'])})")
        if f.get("mass_span"):
            lines.append("    mass span at one length (straight, lightest scale with cavities to heaviest with balls):")
            lines += [f"      {m['length']:g} mm: {m['mass'][0]:.2f} to {m['mass'][1]:.2f} g ({m['ratio']:.1f}:1, "
                      f"scale {m['scales'][0]:g} to {m['scales'][1]:.3g})" for m in f["mass_span"]]
    return lines + [""]


def _lookup_deviation(catalog: Catalog, limits: dict[tuple[str, str], Any]) -> dict[str, Any]:
    """How far the fast joint-limit function (:func:`rodcad.catalog.jointlimits.joint_limits`)
    is from the B-rep search on this catalog's pairs: the worst deviation (deg) and
    whether it ever allows more bend than the solids (beyond the search's tolerance)."""
    worst, worst_pair, looser = 0.0, None, []
    for (left, right), r in limits.items():
        if not r.assemblable:
            continue
        fast = joint_limits(catalog[left].geometry, catalog[right].geometry)
        # the search's bound: a contact found at +-180 deg is nothing stopping before it
        brep = [None if b is not None and abs(b) >= 180.0 - 10 * TOLERANCE_DEG else b for b in r.limits_deg]
        for side, (a, b) in enumerate(zip(fast, brep)):
            if a is None or b is None:
                if (a is None) != (b is None):
                    looser.append(f"{left} -> {right}")
                continue
            if abs(a - b) > worst:
                worst, worst_pair = abs(a - b), f"{left} -> {right}"
            if (b - a if side == 0 else a - b) > TOLERANCE_DEG:
                looser.append(f"{left} -> {right}")
    return {"worst_deviation_deg": round(worst, 4), "worst_pair": worst_pair,
            "allows_more_bend_than_the_solids": sorted(set(looser))}


def _compute_tables(catalog: Catalog, *, jobs: int | None, cache: DiskCache | None,
                    progress: bool) -> tuple[dict[str, Any], dict[tuple[str, str], Any]]:
    """Every type's mass info and every joinable pair's limits, computed where not cached.

    Raises:
        InputError: a rod type's parameters make no valid solid.
    """
    from rodcad.catalog import limits as limits_mod
    from rodcad.catalog import massrange as massrange_mod
    from rodcad.catalog.limits import all_pair_limits
    from rodcad.catalog.massrange import mass_infos

    cache = cache if cache is not None else DiskCache()
    # Build every solid that has work left before starting workers, so that
    # parameters making no valid solid are reported as bad input (cached
    # results were computed from solids that built fine).
    needed = {t.name: t for t in catalog.types if not massrange_mod.is_cached(t, cache)}
    for a, b in catalog.pairs():
        if not limits_mod.is_cached(a, b, cache):
            needed.setdefault(a.name, a)
            needed.setdefault(b.name, b)
    from rodcad.cad.solids import type_solid  # (build123d: imported where solids are built)

    for t in needed.values():
        type_solid(t)
    masses = mass_infos(list(catalog.types), jobs=jobs, cache=cache,
                        progress=_progress("mass ranges") if progress else None)
    limits = all_pair_limits(catalog, jobs=jobs, cache=cache,
                             progress=_progress("pair limits") if progress else None)
    return masses, limits


def _sampled_limits(catalog: Catalog, *, jobs: int | None, cache: DiskCache | None,
                    progress: bool) -> tuple[Catalog, dict[tuple[str, str], Any]]:
    """B-rep limits of rods printed to order sampled over their families' ranges
    (:func:`rodcad.catalog.printed.sample_pairs`), with the catalog that knows them."""
    from rodcad.catalog.limits import all_pair_limits
    from rodcad.catalog.printed import sample_pairs

    pairs = [p for f in catalog.printed_families for p in sample_pairs(catalog, f)]
    if not pairs:
        return catalog, {}
    extended = catalog.with_types([t for p in pairs for t in p])
    return extended, all_pair_limits(extended, pairs=pairs, jobs=jobs, cache=cache,
                                     progress=_progress("sampled rods printed to order") if progress else None)


def _limits_json(r: Any) -> list[float | None]:
    return [None if x is None else round(x, 3) for x in r.limits_deg]


def _progress(what: str) -> Any:
    def report(done: int, total: int) -> None:
        end = "\n" if done == total else ""
        print(f"\rrodcad: computing {what}: {done}/{total}", end=end, file=sys.stderr, flush=True)

    return report


def _check(args: argparse.Namespace) -> int:
    catalog = load_catalog(args.catalog)
    cache = DiskCache(enabled=not args.no_cache)
    report = check_report(catalog, jobs=args.jobs, cache=cache, progress=sys.stderr.isatty())
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(_format_report(report))
    for problem in report["problems"]:
        print(problem, file=sys.stderr)
    return 2 if report["problems"] else 0  # a family whose rods cannot be joined: the catalog is wrong


def _fmt_limit(x: float | None) -> str:
    if x is None:
        return "none"
    text = f"{x:.2f}"
    return "0.00" if text == "-0.00" else text


def _fmt_limits(lims: list[float | None] | None) -> str:
    if lims is None:
        return "-"
    return f"[{_fmt_limit(lims[0])}, {_fmt_limit(lims[1])}]"


def _format_report(report: dict[str, Any]) -> str:
    """The human-readable form of :func:`check_report`."""
    types = report["types"]
    lines = [
        f"catalog {report['catalog']} ({report['file']}): {len(types)} rod types, "
        f"{len(report['pairs'])} joinable ordered pairs",
        "",
        *_family_lines(report["families"]),
    ]
    header = ["type", "length", "solid mass", "mass range", "com (along, perp)", "limits with itself",
              "lightest", "heaviest"]
    rows = []
    for t in types:
        balls = t["balls"]
        rows.append([
            t["name"],
            f"{t['length']:g} mm",
            f"{t['solid_mass']:.3f} g",
            f"[{t['mass_range'][0]:.3f}, {t['mass_range'][1]:.3f}] g",
            f"({t['com'][0]:.2f}, {t['com'][1]:.2f}) mm",
            _fmt_limits(t["self_limits_deg"]) + " deg" if t["self_limits_deg"] else "-",
            (f"{t['cavities']['count']} x r{t['cavities']['radius']:.2f}" if t["cavities"]["count"] else
             "1 chamber, empty" if t.get("fill") else "none"),
            (f"{balls['count']} x {ball_text(balls['diameter'], balls.get('kind') or '')}" if balls else
             f"chamber full: {t['fill']['max_g']:.1f} g of {t['fill']['name']}" if t.get("fill") else "none"),
        ])
    widths = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
    lines.append("  ".join(h.ljust(w) for h, w in zip(header, widths)).rstrip())
    for r in rows:
        lines.append("  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip())
    lines.append("")
    lines.append("joint limits [lo, hi] in degrees (bend phi > 0 sags; 'none': no collision up to 180),")
    lines.append("per ordered pair left -> right:")
    by_left: dict[str, dict[str, list[str]]] = {}
    for p in report["pairs"]:
        group = by_left.setdefault(p["left"], {})
        group.setdefault(_fmt_limits(p["limits_deg"]), []).append(p["right"])
    name_w = max((len(n) for n in by_left), default=0)
    for left, groups in by_left.items():
        for lims, rights in groups.items():
            lines.append(f"  {left.ljust(name_w)} -> {lims}: {' '.join(rights)}")
    stats = report["stats"]
    lines.append("")
    lines.append(f"({stats['pairs_computed']} pairs computed, {stats['pairs_cached']} from cache, "
                 f"{stats['seconds']:.1f} s)")
    lk = report["limit_lookup"]
    sampled = (f", {lk['sampled_printed_pairs']} of them rods printed to order sampled over their ranges"
               if lk.get("sampled_printed_pairs") else "")
    lines.append(f"fast joint-limit function against the B-rep search{sampled}: worst deviation "
                 f"{lk['worst_deviation_deg']:.4f} deg ({lk['worst_pair']})"
                 + (f"; allows more bend than the solids at {', '.join(lk['allows_more_bend_than_the_solids'])}"
                    if lk["allows_more_bend_than_the_solids"] else "; never more bend than the solids"))
    return "\n".join(lines)


# --------------------------------------------------------------------------- precompute

#: The cache kinds a seed file holds.
SEED_KINDS = ("limits", "mass", "fabint")


def precompute(catalog: Catalog, *, jobs: int | None = None, progress: bool = False) -> dict[str, Any]:
    """Compute a catalog's seed data from the solids, in a fresh cache with
    the seed layer off.

    Returns:
        ``{"rodcad_seed_cache": 1, "catalog": NAME, "entries": {kind: {key:
        value}}}`` for the kinds of :data:`SEED_KINDS`.
    """
    from rodcad.catalog.printed import mass_table
    from rodcad.fabrication.intervals import chain_intervals

    saved = {k: os.environ.get(k) for k in ("RODCAD_CACHE_DIR", "RODCAD_SEED_CACHE")}
    with tempfile.TemporaryDirectory(prefix="rodcad-precompute-") as tmp:
        # worker processes inherit the environment: they too compute afresh
        os.environ["RODCAD_CACHE_DIR"] = tmp
        os.environ["RODCAD_SEED_CACHE"] = "0"
        try:
            cache = DiskCache(tmp)
            _compute_tables(catalog, jobs=jobs, cache=cache, progress=progress)
            for fam in catalog.printed_families:  # the mass tables of rods printed to order
                mass_table(fam, jobs=jobs)
            _sampled_limits(catalog, jobs=jobs, cache=cache, progress=progress)
            if progress:
                print(f"rodcad: computing achievable mass intervals of {len(catalog)} types ...",
                      file=sys.stderr, flush=True)
            chain_intervals(list(catalog), seed=0, jobs=jobs, cache=cache)
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v
        entries: dict[str, dict[str, Any]] = {}
        for kind in SEED_KINDS:
            table = entries[kind] = {}
            for f in sorted((Path(tmp) / kind).glob("*/*.json")):
                with open(f, encoding="utf-8") as fh:
                    value = json.load(fh)
                if kind == "limits" and isinstance(value, dict) and "seconds" in value:
                    value["seconds"] = 0.0  # timing: unused from the cache, kept out for reproducible files
                table[f.stem] = value
    return {"rodcad_seed_cache": 1, "catalog": catalog.name, "entries": entries}


def _precompute(args: argparse.Namespace) -> int:
    catalog = load_catalog(args.catalog)
    if args.output:
        out = Path(args.output)
    elif catalog.path is not None:
        out = catalog.path.with_name(f"{catalog.path.stem}.cache.json")
    else:  # pragma: no cover - load_catalog always sets the path
        out = Path(f"{catalog.name}.cache.json")
    t0 = time.perf_counter()
    data = precompute(catalog, jobs=args.jobs, progress=sys.stderr.isatty())
    text = json.dumps(data, sort_keys=True, separators=(",", ":")) + "\n"
    try:
        write_atomic(out, text, mode=0o644)  # a file to ship: readable by all
    except OSError as err:
        print(f"rodcad: cannot write {out}: {err.strerror or err}", file=sys.stderr)
        return 1
    counts = ", ".join(f"{len(data['entries'][k])} {k}" for k in SEED_KINDS)
    print(f"catalog {catalog.name}: {counts} entries in {time.perf_counter() - t0:.1f} s -> {out} "
          f"({len(text) / 1024:.0f} KiB)")
    return 0


# --------------------------------------------------------------------------- export


def _export(args: argparse.Namespace) -> int:
    from rodcad.cad.export import export_step

    catalog = load_catalog(args.catalog)
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise InputError([Problem(str(out), 0, 0, "", "exists and is not a directory")])
    from rodcad.cad.solids import type_solid

    solids = [(t, type_solid(t)) for t in catalog.types]  # all or nothing: build before writing
    created = not out.exists()
    staged: list[tuple[Path, Path]] = []
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=out, prefix=".rodcad-export-") as tmp:
            for t, solid in solids:
                part = Path(tmp) / f"{t.name}.step"
                export_step(solid, part, t.name)
                staged.append((part, out / f"{t.name}.step"))
            for part, final in staged:
                os.replace(part, final)
    except OSError as err:
        if created:
            shutil.rmtree(out, ignore_errors=True)
        print(f"rodcad: cannot write {out}: {err.strerror or err}", file=sys.stderr)
        return 1
    for t, solid in solids:
        print(f"{out / (t.name + '.step')}: {t.name}, length {t.length:g} mm, volume {solid.volume:.3f} mm^3")
    return 0


# --------------------------------------------------------------------------- schema


def schema_text() -> str:
    """The catalog JSON Schema as written to ``catalogs/catalog.schema.json``."""
    return json.dumps(catalog_schema(), indent=2) + "\n"


def _schema(args: argparse.Namespace) -> int:
    text = schema_text()
    if args.output:
        try:
            Path(args.output).write_text(text, encoding="utf-8")
        except OSError as err:
            print(f"rodcad: cannot write {args.output}: {err.strerror or err}", file=sys.stderr)
            return 1
    else:
        sys.stdout.write(text)
    return 0
