"""``rodcad check OUTDIR``: how an earlier build hangs with its rods as they are now.

The steps (numbers here, solids through :mod:`rodcad.cad.reread`)::

    OUTDIR/design.json            -> load_built()        rodcad.check.built
    catalog, rod types            -> chain_types()       rodcad.check.types
    rods/*.step (or assembly)     -> read_rods()         rodcad.check.measure: valid closed
                                     solids, rod frame, mass and centre of mass, pin holes
    re-simulation                 -> solve_equilibrium with the measured masses and centres
                                     of mass and the design's joint limits
    joints next to edited rods    -> joint_overlaps()    the rods must not overlap at the new
                                     bends nor inside the design's limits

:func:`check` returns a :class:`CheckResult`; :func:`check_json` is what ``--json`` prints.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from optimize import EquilibriumResult, shape_distance, solve_equilibrium
from optimize.distance import ShapeDistance
from rodcad.check.built import BuiltChain, load_built
from rodcad.check.measure import JointOverlap, RodReading, joint_overlaps, read_rods
from rodcad.check.types import ChainTypes, chain_types
from rodcad.design.hung import hung_com
from rodcad.design.asprinted import AsPrinted, as_printed, fused_joints, plan_of
from rodcad.errors import InputError, Problem
from rodcad.progress import Progress

__all__ = ["CheckResult", "check", "check_json", "equilibrium_json", "simulate"]


@dataclass
class CheckResult:
    """An earlier build with its rods as they are now.

    Attributes:
        built: its design.json.
        types: its catalog and rod types.
        readings: every rod, measured.
        equilibrium: the chain re-simulated with the measured masses and centres of mass.
        vs_design: its joints against design.json's simulated joints.
        vs_target: its joints against the target joints.
        overlaps: joints next to edited rods where the rods now overlap.
        as_printed: the chain with every pin bearing in its holes as printed (design.json
            ``rods[].holes_mm``, ``params.pin_clearance``), the measured masses and centres of
            mass (None for a build without them).
        notes: what the user should know, in sentences.
        time_s: wall time.
    """

    built: BuiltChain
    types: ChainTypes
    readings: list[RodReading]
    equilibrium: EquilibriumResult
    vs_design: ShapeDistance
    vs_target: ShapeDistance
    overlaps: list[JointOverlap]
    notes: list[str] = field(default_factory=list)
    time_s: float = 0.0
    as_printed: AsPrinted | None = None

    @property
    def edited(self) -> list[int]:
        return [r.index for r in self.readings if r.edited]

    @property
    def masses(self) -> np.ndarray:
        return np.array([r.mass for r in self.readings], float)

    @property
    def com(self) -> np.ndarray:
        return np.array([r.com for r in self.readings], float)

    @property
    def blocked(self) -> bool:
        """The chain cannot hang as simulated: rods overlap at the bend it would take."""
        return any(o.where == "pose" for o in self.overlaps)

    @property
    def ok(self) -> bool:
        return self.equilibrium.success and not self.blocked


def simulate(built: BuiltChain, masses: np.ndarray, com: np.ndarray, g: float) -> EquilibriumResult:
    """The chain's equilibrium with these masses and centres of mass, the design's limits."""
    a, b = built.anchors
    return solve_equilibrium(built.lengths, masses, a, b, com=com, limits=built.limits if built.n > 1 else None,
                             g=g, end_limits=built.end_limits)


def with_hardware(built: BuiltChain, masses: np.ndarray, com: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rods' masses and centres of mass as they hang: with the joint hardware's metal
    design.json gives at each rod's hinge axes (``rods[].hardware.metal_g``; none in an
    older build)."""
    rods = built.data.get("rods") or []
    metal = np.array([(r.get("hardware") or {}).get("metal_g", [0.0, 0.0]) for r in rods], float).reshape(-1, 2)
    if metal.shape[0] != len(masses) or not np.any(metal):
        return masses, com
    hung = np.asarray(masses, float) + metal.sum(axis=1)
    return hung, hung_com(hung, com, built.lengths, metal)


def printed(built: BuiltChain, masses: np.ndarray, com: np.ndarray, g: float) -> AsPrinted | None:
    """The chain as printed (pins in their holes) with these masses and centres of mass, the
    holes and clearances design.json gives (the joint hardware's where it has some); None
    where it gives none (an older build)."""
    rods = built.data.get("rods")
    try:
        offsets = [r["holes_mm"] for r in rods]
        clear = [float(r["params"]["pin_clearance"]) for r in rods]
    except (KeyError, TypeError):
        return None
    clear = clear + clear[-1:]
    pins = (built.data.get("hardware") or {}).get("pins")
    if pins and len(pins) == len(clear):
        clear = [0.0 if p.get("option") is None else float(p["clearance_mm"]) for p in pins]
    runs = built.data.get("fused") or []
    plan = plan_of(offsets, clear, built.limits if built.n > 1 else None, fused_joints(runs, built.n))
    return as_printed(lengths=built.lengths, masses=masses, com=com, plan=plan, anchors=built.anchors,
                      target=built.target, limits=built.limits if built.n > 1 else None,
                      end_limits=built.end_limits, g=g)


def check(outdir: str | Path, *, assembly: str | Path | None = None,
          progress: Progress | None = None) -> CheckResult:
    """Re-read the rods of an earlier build and re-simulate the chain.

    Args:
        outdir: the output folder of ``rodcad build`` (with CAD).
        assembly: read the rods from this assembly STEP instead of OUTDIR/rods/*.step.
        progress: where to report progress.

    Raises:
        InputError: OUTDIR is not such a folder, a rod file is not one valid closed solid,
            or a rod's pin holes moved or vanished.
    """
    progress = progress or Progress(quiet=True)
    t0 = time.perf_counter()
    built = load_built(outdir)
    asm = Path(assembly) if assembly is not None else None
    if asm is not None and not asm.is_file():
        raise InputError([Problem(str(asm), 0, 0, "--assembly", "no such file")])
    with progress.step("catalog and rod types of the build"):
        types = chain_types(built)
    with progress.step(f"re-reading {built.n} rods (valid closed solids, pin holes, mass, centre of mass)"):
        readings = read_rods(built, types.rods, assembly=asm)
    masses, com = with_hardware(built, np.array([r.mass for r in readings], float),
                                np.array([r.com for r in readings], float))
    with progress.step("re-simulating the chain (and with every pin bearing in its holes)"):
        eq = simulate(built, masses, com, types.g)
        try:
            ap = printed(built, masses, com, types.g)
        except ValueError:  # the play leaves no configuration: reported by the notes below
            ap = None
    with progress.step("joints next to edited rods (overlaps at the new bends and at the limits)"):
        overlaps = joint_overlaps(built, readings, np.degrees(eq.bends))
    res = CheckResult(built, types, readings, eq, shape_distance(built.simulated, eq.points),
                      shape_distance(built.target, eq.points), overlaps, as_printed=ap)
    res.notes = _notes(res)
    res.time_s = time.perf_counter() - t0
    return res


def _notes(res: CheckResult) -> list[str]:
    notes = []
    edited = res.edited
    span = res.built.span
    if not edited:
        notes.append("no rod was edited: every rod has the mass and centre of mass design.json gives it")
    else:
        d = res.vs_design
        notes.append(f"{len(edited)} edited rod(s) ({', '.join(map(str, edited))}): the chain now hangs up to "
                     f"{d.max:.3g} mm ({100 * d.max / span:.3g} % of the span) from the designed shape; "
                     "`rodcad check --rebalance` re-designs the other rods' masses to bring it back")
    eq = res.equilibrium
    if not eq.success:
        notes.append(f"the equilibrium solver did not converge: {eq.message}")
    elif not eq.stable:
        notes.append("the re-simulated shape is an equilibrium but NOT a stable one")
    ap = res.as_printed
    if ap is not None:
        notes.append(f"as printed (every pin bearing in its holes): the chain hangs {ap.distance.max:.3g} mm "
                     f"({100 * ap.distance.max / span:.3g} % of the span) from the target"
                     + ("" if ap.result.success else f" (the solver: {ap.result.message})"))
    notes += [o.sentence() for o in res.overlaps]
    return notes


def _f(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def equilibrium_json(eq: EquilibriumResult) -> dict[str, Any]:
    """Points, angles, stability of an equilibrium (design.json's ``simulated`` fields)."""
    return {"points": [[float(x), float(y)] for x, y in eq.points],
            "angles_deg": [float(math.degrees(v)) for v in eq.angles],
            "reaction": [_f(v * 1e-3) for v in eq.reaction], "reaction_a": [_f(v * 1e-3) for v in eq.reaction_a],
            "kkt_residual": _f(eq.kkt_residual), "stable": bool(eq.stable), "success": bool(eq.success)}


def _printed_json(res: CheckResult) -> dict[str, Any]:
    """check --json's ``as_printed``: the pins, against the target and against the build's own
    as-printed pins (design.json ``as_printed.points``) where it has them."""
    ap = res.as_printed
    assert ap is not None
    out: dict[str, Any] = {"points": [[float(x), float(y)] for x, y in ap.result.points], "error": ap.distance.as_dict(),
                           "stable": bool(ap.result.stable), "success": bool(ap.result.success)}
    before = (res.built.data.get("as_printed") or {}).get("points")
    if isinstance(before, list) and np.shape(before) == ap.result.points.shape:
        out["error_vs_design"] = shape_distance(np.asarray(before, float), ap.result.points).as_dict()
    return out


def check_json(res: CheckResult) -> dict[str, Any]:
    """What ``rodcad check --json`` prints (contract.md's round trip)."""
    rods = []
    for r, b in zip(res.readings, res.built.rods):
        rods.append({"index": r.index, "type": b.type, "file": str(r.file), "mass": float(r.mass),
                     "com": [float(v) for v in r.com], "edited": bool(r.edited),
                     "plastic_volume_mm3": float(r.volume), "mass_change_rel": float(r.mass_change),
                     "com_shift_mm": float(r.com_shift),
                     "built": {"mass": float(b.mass), "com": [float(v) for v in b.com]}})
    return {
        "name": res.built.data.get("name"), "outdir": str(res.built.outdir), "catalog": res.built.catalog,
        "rods": rods,
        "edited": res.edited,
        "simulated": equilibrium_json(res.equilibrium),
        "error_vs_design": res.vs_design.as_dict(),
        "error": res.vs_target.as_dict(),
        "as_printed": None if res.as_printed is None else _printed_json(res),
        "joints": [{"joint": o.joint, "bend_deg": o.bend_deg, "where": o.where, "overlap_mm3": o.overlap}
                   for o in res.overlaps],
        "ok": bool(res.ok),
        "notes": list(res.notes),
        "time_s": float(res.time_s),
    }
