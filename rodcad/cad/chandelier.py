"""A chandelier's solids: the frame with its lugs, checked against the hanging rods, and
the assembly nodes (frame, chains, pins) for assembly.step.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rodcad.cad.export import AssemblyGroup, AssemblyPart, rod_matrices, rod_matrix
from rodcad.cad.chainfiles import chain_parts
from rodcad.cad.solids import type_solid
from rodcad.design.chandelier import ChainResult
from rodcad.design.frame import FrameCheck, FramePlan

__all__ = ['rod_matrices', 'build_frame', 'chandelier_nodes']






def build_frame(plan: FramePlan, catalog: Any, chains: Sequence[ChainResult] | None = None, *,
                check_clearance: bool = True) -> tuple[Any, FrameCheck]:
    """Build the frame solid and check it.

    Checks: one valid solid; its bounding box against the catalog printer's
    build volume; every rod's actual solid at its rest pose (when ``chains`` are
    given; rods whose boxes are apart from the frame's are skipped) and, per lug,
    the end rod hanging straight away from the frame (down from a frame above):
    none may touch the frame.

    Returns:
        (build123d Solid, FrameCheck).

    Raises:
        rodcad.cad.solids.GeometryError: the parameters make no single valid solid.
    """
    from rodcad.cad.collision import DistanceTo
    from rodcad.cad.export import placed
    from rodcad.cad.frame import frame_solid
    from rodcad.cad.solids import is_valid_solid

    solid = frame_solid(plan.kind, plan.params, plan.lugs)
    problems: list[str] = []
    valid = is_valid_solid(solid)
    if not valid:  # pragma: no cover - frame_solid raises first
        problems.append("the frame is not one valid solid")
    bb = solid.bounding_box()
    size = (float(bb.size.X), float(bb.size.Y), float(bb.size.Z))
    printer = getattr(catalog, "printer", None)
    fits = None
    vol = None
    if printer is not None:
        vol = tuple(float(x) for x in printer.build_volume)
        fits = bool(np.all(np.sort(size) <= np.sort(vol) + 1e-9))
        if not fits:
            problems.append(f"the frame ({size[0]:.0f} x {size[1]:.0f} x {size[2]:.0f} mm) does not "
                            f"fit the printer's build volume {vol[0]:.0f} x {vol[1]:.0f} x "
                            f"{vol[2]:.0f} mm")
    clear: list[tuple[str, str, float]] = []
    if check_clearance:
        near = DistanceTo(solid)
        lo = np.array([bb.min.X, bb.min.Y, bb.min.Z]) - 1.0
        hi = np.array([bb.max.X, bb.max.Y, bb.max.Z]) + 1.0

        def distance(rod_solid: Any) -> float | None:
            rb = rod_solid.bounding_box()
            if np.any(np.array([rb.min.X, rb.min.Y, rb.min.Z]) > hi) or np.any(
                    np.array([rb.max.X, rb.max.Y, rb.max.Z]) < lo):
                return None  # nowhere near the frame
            return near(rod_solid)

        # every rod at rest
        for c in chains or []:
            base = c.placement.transform()
            for i, (type_name, m) in enumerate(zip(c.type_names, rod_matrices(c.points))):
                d = distance(placed(type_solid(catalog[type_name]), base @ m))
                if d is None:
                    continue
                clear.append((f"{c.name}.rod_{i:02d}", "rest", d))
                if d <= 1e-6:
                    problems.append(f"{c.name}: rod {i} ({type_name}) touches the frame at rest")
        # the end rods hanging straight away from the frame
        for k, lug in enumerate(plan.lugs):
            chain_i, end = divmod(k, 2)
            if chains is not None:
                type_name = chains[chain_i].type_names[-1 if end else 0]
            else:
                type_name = catalog.names[0]
            rod = catalog[type_name]
            s = 1.0 if lug.attach_dz > 0 else -1.0
            theta = -s * math.pi / 2 if end == 0 else s * math.pi / 2
            origin = (0.0, 0.0) if end == 0 else (-rod.length * math.cos(theta),
                                                   -rod.length * math.sin(theta))
            d = near(placed(type_solid(rod), lug.location @ rod_matrix(origin, theta)))
            clear.append((lug.name, "free", d))
            if d <= 1e-6:
                problems.append(f"{lug.name}: the {type_name} rod touches the frame when hanging "
                                f"straight {'down' if s > 0 else 'up'} from it")
    return solid, FrameCheck(valid, size, fits, vol, clear, problems)


def chandelier_nodes(frame: Any, chains: Sequence[ChainResult], catalog: Any, *,
                     rod_solid: Callable[[int, int], Any] | None = None,
                     frame_plan: FramePlan | None = None,
                     pin_diameters: Sequence[Sequence[float | None] | None] | None = None) -> list[Any]:
    """The node tree of the whole chandelier for :func:`rodcad.cad.export.export_assembly`.

    Top level: the part 'frame' (world placement) and one group per chain, named
    after it ('chain_01', ...), located by the chain's :meth:`ChainPlacement.transform`.
    A chain group holds its rods 'NN_TYPE' (as the rods/ files: rod i with its rod frame at joint p_i,
    x along p_i -> p_{i+1}, coloured by mass on one scale for all chains) and its
    pins 'pin_00'.. (one per joint; the two anchor pins are as long as their lugs).

    Args:
        frame: the frame solid (or None for no frame).
        chains: designed chains.
        catalog: the rod catalog (rod solids and pin sizes).
        rod_solid: ``(chain index, rod index) -> Solid`` for the as-built rods
            (with cavities / sockets); default: the catalog type's plain solid.
        frame_plan: the frame's plan, for the anchor pin lengths (default: the
            rod thickness plus the layer gaps and the prongs).
        pin_diameters: per chain, each pin's diameter (its joint hardware's, mm), or None:
            the family's pin.
    """
    all_m = np.concatenate([c.masses for c in chains])
    scale = (float(all_m.min()), float(all_m.max()))
    nodes: list[Any] = []
    if frame is not None:
        nodes.append(AssemblyPart("frame", frame, np.eye(4), (0.6, 0.6, 0.62)))
    for ci, c in enumerate(chains):
        n = len(c.type_names)
        solids = [rod_solid(ci, i) if rod_solid is not None else type_solid(catalog[name])
                  for i, name in enumerate(c.type_names)]
        pins = []
        for j in range(n + 1):
            g = catalog[c.type_names[min(j, n - 1)]].geometry
            length = g.thickness
            if j in (0, n):  # through a lug: a fork lug's cheeks add to the rod's thickness
                if frame_plan is not None:
                    length = frame_plan.lugs[2 * ci + (1 if j == n else 0)].width
                else:
                    length = 2 * g.thickness - g.hinge.tongue_thickness
            own = None if pin_diameters is None or pin_diameters[ci] is None else pin_diameters[ci][j]
            pins.append((g.hinge.pin_diameter if own is None else own, length))
        children = chain_parts([f"{i:02d}_{name}" for i, name in enumerate(c.type_names)], solids, c.points,
                               c.masses, pins, mass_scale=scale)
        nodes.append(AssemblyGroup(c.name, children, c.placement.transform()))
    return nodes
