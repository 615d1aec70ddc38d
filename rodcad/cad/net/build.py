"""A net's solids built and written: every distinct rod and hub built once, as a task
(:func:`build_group`: numbers in; BREP, checked STEP and STL bytes and numbers out) that runs in
this process, in worker processes or on a Dask cluster with the same result
(:func:`rodcad.parallel.task_runner`); the members' instances of them, the net re-solved as
built (:func:`build_net_solids` -> :class:`rodcad.cad.net.solids.NetSolids`); their files, each
distinct part once, and assembly.step with every instance where the net hangs
(:func:`write_net_files`).

Which parts are one: :mod:`rodcad.cad.net.parts`. The solids: :mod:`rodcad.cad.net.solids`,
:mod:`rodcad.cad.net.bent`, :mod:`rodcad.cad.net.hub`.

Units: mm, g.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from pathlib import Path

import numpy as np
from build123d import CenterOf, Solid

from rodcad.cad.export import (AssemblyPart, check_files, export_instanced_assembly, export_step, export_stl,
                               matrix_location)
from rodcad.cad.mesh import print_deflection
from rodcad.cad.net.bent import bent_rod_solid, bent_socket_centres
from rodcad.cad.net.hub import HubSplit, split_hub, split_plane, splittable_sockets
from rodcad.cad.net.parts import (REL_TOL, HubSpec, PartResult, PartTask, RodSpec, brep_bytes, from_brep,
                                  group_parts, signature)
from rodcad.cad.net.solids import AS_BUILT_KKT, NetPart, NetSolids, hub_solid, net_rod_solid, whole_hub
from rodcad.cad.net.splice import spliced_rod, spliced_rod_solids
from rodcad.cad.solids import GeometryError, precise_volume
from rodcad.catalog.net.splice import splice_fill
from rodcad.design.net.frames import place, rod_matrix

__all__ = ["build_group", "build_net_solids", "distinct_count", "part_specs", "write_net_files"]


def part_specs(check) -> tuple[list, list]:
    """What every rod and hub of a designed net is built from: (rod specs, per rod; hub specs,
    per node, None for a node no rod reaches), :mod:`rodcad.cad.net.parts`. A hub's sockets are
    widened where one cut would not admit its balls otherwise (:func:`splittable_sockets`) and
    its hardware carries the clearance it is cut with."""
    plan = check.plan
    t, hw = plan.target, plan.hardware
    rods = []
    fill, arcs = plan.fill_lengths, plan.arcs
    for e, k in enumerate(plan.rod_pieces):
        L, mass = float(plan.lengths[e]), float(check.masses[e])
        if k > 1:  # spliced: each piece's own balls and cavity
            fills, _ = splice_fill(hw, L, mass, int(k))
            rods.append(RodSpec(hw, L, sum(b for b, _ in fills), sum(c for _, c in fills), None,
                                tuple((int(b), float(c)) for b, c in fills)))
            continue
        balls, cavity, _ = hw.rod_fill(float(fill[e]), mass)
        rods.append(RodSpec(hw, L, int(balls), float(cavity), arcs[e]))
    hubs = []
    ends = t.node_ends()
    for k in range(t.n if hw.is_hub else 0):
        at = ends[k]
        if not at:  # an anchor no rod reaches (a boundary-held grid's corner): no hub to print
            hubs.append(None)
            continue
        socks = np.array([check.sockets[e, c] for e, c in at]).reshape(-1, 3)
        piv = np.array([plan.pivots[e, c] for e, c in at]).reshape(-1, 3)
        socks, clear = splittable_sockets(socks, piv, hw.clearance, hw.ball)
        hwk = plan.hub(k)  # its own size of the catalog's hub family
        hwk = hwk if clear == hw.clearance else dataclasses.replace(hwk, clearance=clear)
        hubs.append(HubSpec(hwk, tuple(map(tuple, np.asarray(socks, float)))))
    return rods, hubs


def distinct_count(check) -> int:
    """How many distinct parts (tasks) a designed net's CAD build has: its rods' and hubs'
    groups (:func:`rodcad.cad.net.parts.group_parts`)."""
    rods, hubs = part_specs(check)
    return len(group_parts(rods)) + len(group_parts([h for h in hubs if h is not None]))


def build_net_solids(check, *, printer=None, layer_height: float = 0.2, runner=None,
                     progress=None) -> NetSolids:
    """Every distinct hub and rod of a :class:`rodcad.design.net.check.NetCheck` built once
    (:mod:`rodcad.cad.net.parts`: equal parts found from what they are built from, confirmed on
    their own B-rep), their files written and checked, and the net re-solved with every
    member's own solid's mass and centre of mass.

    Args:
        check: the designed net (each rod's balls and cavity from NodeHardware.rod_fill).
        printer, layer_height: the catalog's printer and the print's layer height (mm): the
            STL and 3MF meshes' deflection (:func:`rodcad.cad.mesh.print_deflection`).
        runner: runs the parts' tasks, ``runner(fn, tasks) -> results`` in order
            (:func:`rodcad.parallel.task_runner`); default: in this process.
        progress: a progress step (``count``) or None.
    """
    from optimize import solve_net

    plan = check.plan
    t, hw = plan.target, plan.hardware
    defl = print_deflection(printer, layer_height)
    ball_mass = hw.insert_density * math.pi / 6 * hw.insert_diameter ** 3 / 1000.0
    rho = hw.density / 1000.0
    rod_specs, hub_specs = part_specs(check)
    hub_nodes = [k for k, h in enumerate(hub_specs) if h is not None]
    tasks, owners = [], []
    for kind, specs, idx in (("rod", rod_specs, list(range(t.m))), ("hub", [hub_specs[k] for k in hub_nodes], hub_nodes)):
        for group in group_parts(specs):
            members = [idx[i] for i in group.members]
            label = f"{kind}-{members[0]:03d}"
            tasks.append(PartTask(kind, [specs[i] for i in group.members], label, defl))
            owners.append((kind, members, group.rotations))
    results = _run(tasks, owners, runner, progress)
    rods: list = [None] * t.m
    hubs: list = [None] * t.n if hw.is_hub else []
    splits = [HubSplit([], [], np.array([0.0, 0.0, 1.0]), 0.0, 0.0) for _ in range(len(hubs))]
    rod_masses, rod_balls = np.zeros(t.m), [int(sp.balls) for sp in rod_specs]
    pin_mass = hw.splice.pin_mass
    rod_com = np.column_stack([plan.lengths / 2, np.zeros((t.m, 2))])
    node_masses, node_com = plan.node_masses.copy(), plan.node_com.copy()
    parts = []
    for (kind, members, rotations), res in zip(owners, results):
        shared = [from_brep(data, label) for label, data in res.solids]
        whole = from_brep(res.whole, f"{kind}-{members[0]:03d}") if res.whole else None  # (a split hub, a spliced rod)
        part = NetPart(kind, f"{kind}-{members[0]:03d}", members, rotations, shared, res.print_matrices, res.files,
                       res.mesh_volumes, res.split_reason, list(res.copies), whole if kind == "rod" else None)
        parts.append(part)
        for i, (who, R) in enumerate(zip(members, rotations)):
            if kind == "rod":
                sp = rod_specs[who]
                rods[who] = _instance(part.hanging, np.eye(3), f"rod-{who:03d}")
                rod_masses[who] = rho * res.volumes[i] + sp.balls * ball_mass + (sp.pieces - 1) * pin_mass
                if sp.arc is not None:  # measured on the solid: its plastic's centre of mass and its steel balls
                    moment = rho * res.volumes[i] * res.com[i] + ball_mass * bent_socket_centres(hw, sp.arc, sp.balls).sum(axis=0)
                    rod_com[who] = moment / rod_masses[who]
                continue
            name = f"hub-{who:03d}"
            one = len(shared) == 1
            inst = [_instance(p, R, name if one else f"{name}-{p.label[-1]}") for p in shared]
            hubs[who] = inst[0] if one else _instance(whole, R, name)
            mats = [np.asarray(m, float) @ place(R.T, np.zeros(3)) for m in res.print_matrices]
            spec = hub_specs[who]
            splits[who] = HubSplit(inst, mats, R @ res.normal, res.offset, res.off_plane, res.split_reason,
                                   clearance=spec.hardware.clearance)
            node_masses[who] = rho * res.volumes[i]
            node_com[who] = res.com[i]
    eq = check.equilibrium
    res = solve_net(eq.positions, t.edges, plan.lengths, rod_masses, t.anchored, node_masses=node_masses,
                    node_com=node_com, pivots=plan.pivots, node_rotations0=eq.rotations,
                    com=rod_com if plan.bent else None)
    out = NetSolids(hubs, rods, rod_masses, node_masses, node_com, res, rod_balls=rod_balls,
                    hub_splits=splits if hw.is_hub else [], rod_com=rod_com, parts=parts, deflection=defl,
                    rod_fills=[sp.fills for sp in rod_specs])
    if res.success or (np.isfinite(res.kkt_residual) and res.kkt_residual <= AS_BUILT_KKT
                       and np.all(np.isfinite(res.positions))):
        err = max(float(np.max(np.linalg.norm(res.positions - eq.positions, axis=1))),
                  float(np.max(np.linalg.norm(res.ends - eq.ends, axis=2))))
        out.error_mm, out.rel_size = err, err / t.size
    return out


def _instance(solid, R: np.ndarray, label: str):
    """``solid`` turned by R (its shape shared, not copied), labelled."""
    s = solid.moved(matrix_location(place(R, np.zeros(3)))) if not np.allclose(R, np.eye(3)) else Solid(solid.wrapped)
    s.label = label
    return s


def _run(tasks: list, owners: list, runner, progress) -> list:
    """The tasks' results, in order; members whose B-rep does not confirm their group's part
    are built again as parts of their own (``owners`` and ``tasks`` updated to match)."""
    from rodcad.parallel import in_process

    run = runner or in_process
    count = None if progress is None else progress.count
    results = list(run(build_group, tasks, progress=count))
    extra_tasks, extra_owners = [], []
    for task, (kind, members, rotations), res in zip(list(tasks), list(owners), list(results)):
        for i in [i for i, ok in enumerate(res.confirmed) if not ok]:
            extra_tasks.append(PartTask(kind, [task.specs[i]], f"{kind}-{members[i]:03d}", task.deflection))
            extra_owners.append((kind, [members[i]], [np.eye(3)]))
    if extra_tasks:
        for k, res in enumerate(results):  # drop the unconfirmed members from their groups
            keep = [i for i, ok in enumerate(res.confirmed) if ok]
            kind, members, rotations = owners[k]
            owners[k] = (kind, [members[i] for i in keep], [rotations[i] for i in keep])
            res.volumes = [res.volumes[i] for i in keep]
            res.com = res.com[keep]
        tasks += extra_tasks
        owners += extra_owners
        results += list(run(build_group, extra_tasks, progress=count))
    if progress is not None:
        progress.count(len(tasks), len(tasks))
    return results


def _bare(kind: str, spec, label: str):
    """A member's solid as built from its spec (a hub whole, its sphere's pole on its cut
    plane's normal, as :func:`build_net_solids` cuts it)."""
    if kind == "rod":
        if spec.fills:
            return spliced_rod(spec.hardware, spec.length, spec.fills, name=label)
        if spec.arc is None:
            return net_rod_solid(spec.hardware, spec.length, spec.balls, spec.cavity, name=label)
        return bent_rod_solid(spec.hardware, spec.arc, spec.balls, spec.cavity, name=label)
    socks = np.asarray(spec.sockets, float).reshape(-1, 3)
    return hub_solid(spec.hardware, socks, name=label, pole=split_plane(socks)[0])


def _files(solid, label: str, deflection: tuple[float, float]) -> tuple[dict[str, bytes], float]:
    """The solid's STEP and STL, checked (:func:`rodcad.cad.export.check_files`), as bytes, and
    the STL's volume."""
    import trimesh

    with tempfile.TemporaryDirectory() as tmp:
        step, stl = Path(tmp) / f"{label}.step", Path(tmp) / f"{label}.stl"
        export_step(solid, step, name=label)
        export_stl(solid, stl, tolerance=deflection[0], angular_tolerance=deflection[1])
        check_files(step, stl, precise_volume(solid), deflection=deflection[0], coarse=True, precise=True)
        vol = float(trimesh.load(str(stl), force="mesh").volume)
        return {".step": step.read_bytes(), ".stl": stl.read_bytes()}, vol


def build_group(task: PartTask) -> PartResult:
    """Build one group's part (and its halves, a hub), write and check its files, and confirm
    every other member on its own bare B-rep (module docstring)."""
    spliced = task.kind == "rod" and bool(task.specs[0].fills)
    if spliced:  # the whole rod (its members' signature) and the pieces printed
        spec = task.specs[0]
        first, pieces = spliced_rod_solids(spec.hardware, spec.length, spec.fills, name=task.label)
    else:
        first = _bare(task.kind, task.specs[0], task.label)
    sig0 = signature(first)
    volumes, com, confirmed = [], [], []
    for i, spec in enumerate(task.specs):
        s = first if i == 0 else _bare(task.kind, spec, task.label)
        sig = sig0 if i == 0 else signature(s)
        confirmed.append(bool(np.all(np.abs(sig - sig0) <= REL_TOL * np.abs(sig0))))
        volumes.append(float(s.volume))
        com.append(tuple(s.center(CenterOf.MASS)))
    out = PartResult([], [], [], volumes, np.array(com, float), confirmed)
    printed, mats = [first], [np.eye(4)]
    if spliced:  # the two end pieces are one solid turned end for end, the middle ones another
        printed = pieces[:2] if len(pieces) > 2 else pieces[:1]
        out.copies = [2, len(pieces) - 2][: len(printed)]
        mats = [np.eye(4)] * len(printed)
        out.whole = brep_bytes(first)
    if task.kind == "hub":
        spec = task.specs[0]
        socks = np.asarray(spec.sockets, float).reshape(-1, 3)
        split = split_hub(first, socks, spec.hardware, task.label)
        out.split_reason, out.off_plane, out.offset = split.reason, float(split.off_plane), float(split.offset)
        out.normal = np.asarray(split.normal, float)
        if split.split:
            printed, mats = split.parts, split.print_matrices
            out.whole = brep_bytes(first)
        else:  # printed whole: a sphere's parametrisation that writes to STEP as built
            printed = [whole_hub(spec.hardware, socks, name=task.label)]
    for s, m in zip(printed, mats):
        files, vol = _files(s, s.label, task.deflection)
        out.solids.append((s.label, brep_bytes(s)))
        out.files.append(files)
        out.print_matrices.append(np.asarray(m, float))
        out.mesh_volumes.append(vol)
    return out


def write_net_files(check, solids: NetSolids, folder: Path, *, name: str, progress=None) -> list[str]:
    """Each distinct part's files, once: rods/rod-NNN.step/.stl, hubs/hub-NNN-a.step/.stl and -b
    (a hub's halves; hub-NNN for a hub printed whole), named after the part's first member,
    as built and checked by its task (the STEP re-imports as one valid solid of the same volume,
    the STL is watertight); and assembly.step: every rod and hub part where the designed net
    hangs, each an instance of its part's shape (written once) named after its own rod or
    node, rods coloured light (blue) to heavy (red)."""
    import matplotlib

    written = []
    for part in solids.parts:
        sub = folder / ("rods" if part.kind == "rod" else "hubs")
        sub.mkdir(exist_ok=True)
        for s, files in zip(part.solids, part.files):
            for suffix, data in files.items():
                (sub / f"{s.label}{suffix}").write_bytes(data)
                written.append(f"{sub.name}/{s.label}{suffix}")
    if progress is not None:
        progress.count(len(solids.parts), len(solids.parts))
    eq = check.equilibrium
    m = solids.rod_masses
    norm = matplotlib.colors.Normalize(float(m.min()), float(m.max()) if m.max() > m.min() else float(m.min()) + 1e-9)
    cmap = matplotlib.colormaps["coolwarm"]
    rods, hubs = [], []
    for part in solids.parts:
        for who, R in zip(part.members, part.rotations):
            if part.kind == "rod":
                p0, p1 = eq.ends[who]
                color = tuple(float(c) for c in cmap(norm(m[part.members[0]]))[:3])
                rods.append((who, AssemblyPart(f"rod-{who:03d}", part.hanging, rod_matrix(p0, p1), color)))
                continue
            at = place(eq.rotations[who], eq.positions[who]) @ place(R, np.zeros(3))
            for i, s in enumerate(part.solids):
                grey = 0.8 - 0.15 * i  # the halves of a hub in two greys
                label = f"hub-{who:03d}" + (s.label[len(part.label):] if len(part.solids) > 1 else "")
                hubs.append((who, AssemblyPart(label, s, at, (grey, grey, grey))))
    nodes = [p for _, p in sorted(rods, key=lambda x: x[0])] + [p for _, p in sorted(hubs, key=lambda x: (x[0], x[1].name))]
    if not nodes:  # pragma: no cover - a net has rods
        raise GeometryError("nothing to assemble")
    export_instanced_assembly(folder / "assembly.step", nodes, name=name)
    written.append("assembly.step")
    return written
