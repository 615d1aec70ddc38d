"""``rodcad calibrate friction``: a printable coupon that measures a joint's friction, and
the arithmetic that turns its readings into the catalog's ``friction: [lo, hi]``.

* ``rodcad calibrate friction [CATALOG] [--pin NAME] [-o DIR]`` writes DIR (default
  ``outputs/calibrate-<pin>``): coupon.step (the stand and the wheel, named solids),
  stand.stl and wheel.stl (as they print), coupon.3mf (a PrusaSlicer project with the
  catalog's print profile) and calibrate.md (parts, assembly, how to read, the formula with
  this coupon's numbers, a table from angle to mu). Written to a temporary folder and renamed
  into place at the end, like ``rodcad build``.
* ``rodcad calibrate friction [CATALOG] [--pin NAME] --angle DEG [--angle DEG ...]
  [--rider R_MM] [--ballast N] [--wheel-mass G]`` computes mu from readings (``--rider``
  and ``--ballast`` once for all, or once per ``--angle``) and prints mu per reading, their
  range and the YAML to paste into the catalog's ``pins: options:`` list.

CATALOG is a path or the name of a shipped catalog (default the shipped default,
pla-parametric); the pin, an option of its joint hardware menu (default the families' own).
Bad input exits 2 with ``FILE:LINE:COL: key: message`` lines.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rodcad.catalog.coupon import CouponError, CouponGeometry, Reading, coupon_geometry, default_rider, fit_friction
from rodcad.catalog.loader import load_catalog
from rodcad.catalog.pins import PinOption
from rodcad.design.model import DEFAULT_CATALOG
from rodcad.commands.group import command_group
from rodcad.errors import InputError, Problem
from rodcad.outdir import OutputFolderError, check_output_folder, staged_output
from rodcad.yamlio import suggest

__all__ = ["register", "run_friction"]


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``calibrate`` command and its ``friction`` subcommand."""
    sub = command_group(subparsers, "calibrate",
                        help="print a coupon that measures your joints' friction; turn its readings into catalog "
                        "numbers", description="Calibration coupons for the catalog's numbers that come from tables.",
                        dest="calibrate_command")
    f = sub.add_parser(
        "friction",
        help="a wheel-on-a-pin coupon for one joint hardware option, or mu from its readings",
        description="Without --angle: write a printable coupon (a stand with an angle scale and a balanced "
        "wheel with ball cups) for one joint hardware option of the catalog, and calibrate.md saying how to "
        "assemble and read it. With --angle: the friction coefficient from readings (the largest angle at "
        "which the rider holds), and the YAML to paste into the catalog.",
    )
    f.add_argument("catalog", nargs="?", default=DEFAULT_CATALOG, metavar="CATALOG",
                   help=f"catalog file, or name of a shipped catalog (default {DEFAULT_CATALOG})")
    f.add_argument("--pin", metavar="NAME", help="joint hardware option (default: the catalog's own pin)")
    f.add_argument("-o", "--outdir", metavar="DIR", help="output folder (default outputs/calibrate-<pin>)")
    f.add_argument("--angle", type=float, action="append", metavar="DEG",
                   help="a reading: the largest angle that held, rider from straight below (deg, 0 to <90; repeat)")
    f.add_argument("--rider", type=float, action="append", metavar="R_MM",
                   help="the rider's radius (mm; default the coupon's for this hardware; once, or per --angle)")
    f.add_argument("--ballast", type=int, action="append", metavar="N",
                   help="ballast balls on the wheel (in pairs; default 0; once, or per --angle)")
    f.add_argument("--wheel-mass", type=float, metavar="G",
                   help="the weighed wheel with its sleeve or bearings, without balls or pin (g; default the model's)")
    f.set_defaults(handler=run_friction)


def _per_reading(name: str, values: list | None, n: int, default) -> tuple[list, list[Problem]]:
    """``values`` given once (for all) or once per reading."""
    if not values:
        return [default] * n, []
    if len(values) == 1:
        return values * n, []
    if len(values) == n:
        return list(values), []
    return [], [Problem(" ".join(f"{v:g}" for v in values), 0, 0, name,
                        f"give it once (for every reading) or once per --angle ({n}), not {len(values)} times")]


def _option(catalog, args: argparse.Namespace) -> tuple[PinOption | None, list[Problem]]:
    """The option ``--pin`` names (default the families' own), or a problem."""
    menu = catalog.pins
    if args.pin is None:
        return menu.base, []
    names = [o.name for o in menu.options]
    if args.pin not in names:
        return None, [Problem(args.pin, 0, 0, "--pin", f"no joint hardware {args.pin!r} in catalog "
                              f"{catalog.name!r}{suggest(args.pin, names)}")]
    return menu.option(args.pin), []


def _has_block(catalog) -> bool:
    """The catalog file has a ``pins: options:`` list of its own."""
    if catalog.path is None:
        return False
    import yaml

    try:
        data = yaml.safe_load(Path(catalog.path).read_text(encoding="utf-8")) or {}
    except (OSError, yaml.YAMLError):
        return False
    return isinstance(data, dict) and isinstance(data.get("pins"), dict) and "options" in data["pins"]


def run_friction(args: argparse.Namespace) -> int:
    catalog = load_catalog(args.catalog)
    if catalog.pins is None or not catalog.types:
        raise InputError([Problem(args.catalog, 0, 0, "pins", "the catalog has no joint hardware to measure")])
    option, problems = _option(catalog, args)
    geom = None
    if option is not None:
        try:
            geom = coupon_geometry(catalog, option)
        except CouponError as err:
            problems.append(Problem(option.name, 0, 0, "--pin", f"does not fit a coupon of catalog "
                                    f"{catalog.name!r}: {err}"))
    if args.angle:
        return _readings(catalog, geom, args, problems)
    problems += [Problem(f"{v:g}", 0, 0, key, "is for readings: give --angle too")
                 for key, v in (("--rider", (args.rider or [None])[0]), ("--ballast", (args.ballast or [None])[0]),
                                ("--wheel-mass", args.wheel_mass)) if v is not None]
    name = option.name if option is not None else str(args.pin)
    outdir = Path(args.outdir) if args.outdir else Path("outputs") / f"calibrate-{name}"
    try:
        check_output_folder(outdir)
    except (OutputFolderError, ValueError) as err:
        problems.append(Problem(str(outdir), 0, 0, "-o" if args.outdir else "--pin", str(err)))
    if problems or geom is None:
        raise InputError(problems)
    return _build(catalog, geom, outdir, args)


def _readings(catalog, geom: CouponGeometry | None, args: argparse.Namespace, problems: list[Problem]) -> int:
    from rodcad.outputs.calibrate import readings_text

    n = len(args.angle)
    problems += [Problem(f"{a:g}", 0, 0, "--angle", "must be at least 0 and below 90 degrees (the rider from "
                        "straight below)") for a in args.angle if not (0 <= a < 90)]
    if args.outdir:
        problems.append(Problem(args.outdir, 0, 0, "-o", "nothing is written with --angle; leave -o out"))
    if args.wheel_mass is not None and not (args.wheel_mass > 0 and math.isfinite(args.wheel_mass)):
        problems.append(Problem(f"{args.wheel_mass:g}", 0, 0, "--wheel-mass", "must be above 0 g"))
    if geom is None:
        raise InputError(problems)
    wheel = args.wheel_mass if args.wheel_mass is not None and args.wheel_mass > 0 else geom.wheel_mass()
    radius = default_rider(geom, wheel)[0]
    riders, p1 = _per_reading("--rider", args.rider, n, radius)
    ballast, p2 = _per_reading("--ballast", args.ballast, n, 0)
    problems += p1 + p2
    problems += [Problem(f"{r:g}", 0, 0, "--rider", "must be above 0 mm") for r in set(riders)
                 if not (r > 0 and math.isfinite(r))]
    most = 2 * geom.ballast_pairs
    problems += [Problem(str(b), 0, 0, "--ballast", f"balls go in pairs: give an even number from 0 to {most}")
                 for b in sorted(set(ballast)) if b < 0 or b % 2 or b > most]
    if problems:
        raise InputError(problems)
    readings = [Reading(a, r, geom.ball_mass, wheel + geom.ball_mass * (1 + b))
                for a, r, b in zip(args.angle, riders, ballast)]
    fit = fit_friction(readings, geom.option.radius)
    if args.wheel_mass is None:
        print(f"wheel: {wheel:.2f} g from the model (weigh it and give --wheel-mass for better)")
    print(readings_text(geom, readings, fit, catalog.pins.options, _has_block(catalog)), end="")
    return 0 if 0 <= fit.friction[0] <= fit.friction[1] <= 2 else 1


def _build(catalog, geom: CouponGeometry, outdir: Path, args: argparse.Namespace) -> int:
    from rodcad.cad.coupon import build_coupon, write_coupon
    from rodcad.outputs.calibrate import calibrate_md

    build = build_coupon(geom)
    command = "rodcad calibrate friction " + (args.catalog + " " if args.catalog != DEFAULT_CATALOG else "") + \
        f"--pin {geom.option.name}"
    with staged_output(outdir) as tmp:
        try:
            write_coupon(build, tmp, profile=catalog.print_settings, printer=catalog.printer)
        except CouponError as err:
            raise InputError([Problem(geom.option.name, 0, 0, "--pin", str(err))]) from None
        (tmp / "calibrate.md").write_text(calibrate_md(geom, wheel_volume=build.wheel_volume,
                                                       wheel_mass=build.wheel_mass, menu=catalog.pins.options,
                                                       command=command, profile=catalog.print_settings),
                                          encoding="utf-8")
    rider, beta = default_rider(geom, build.wheel_mass)
    print(f"{outdir}: friction coupon for {geom.option.name} ({geom.catalog}): coupon.step, stand.stl, wheel.stl, "
          f"coupon.3mf, calibrate.md; wheel {build.wheel_mass:.2f} g, rider at {rider:g} mm "
          f"(about {beta:.0f} deg at the tables' mid-range friction)")
    return 0
