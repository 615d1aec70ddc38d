"""A built chain's files: every rod's STEP and STL (checked on re-read) and the assembly in
its hanging pose (:func:`chain_parts`: the parts of one chain placed and coloured by mass,
also a chandelier's and a re-balanced chain's)."""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.cad.export import AssemblyPart, check_files, export_assembly, rod_matrices
from rodcad.cad.frame import pin_solid
from rodcad.cad.rods import ChainFabrication
from rodcad.colors import mass_colors

__all__ = ["RodFiles", "chain_parts", "start_rod_files", "write_assembly", "write_rod_files"]


def write_rod_files(fab: ChainFabrication, outdir: Path, *, jobs: int | None = 1) -> list[Path]:
    """Write outdir/rods/NN_TYPE.step and .stl for every chain position (one NN-MM_piece
    file for the rods of a fused piece, :attr:`ChainFabrication.parts`).

    NN is the rod's 0-based index (as in design.json), two digits or more.
    The solids are in print orientation on the bed (rod frame +y up, the -y
    face on Z = 0, see :data:`rodcad.cad.export.PRINT_ROTATION`). Rods that share
    a solid are written and checked once, then copied. Checks: the STEP
    re-imports as one valid solid of the same volume (1e-6), the STL is
    watertight and encloses the B-rep's volume within 0.1 %. Each rod keeps its STL's mesh
    (:attr:`FabricatedRod.mesh`, rod frame) for the print files. ``jobs``: as
    :func:`start_rod_files`.

    Returns:
        The paths written (STEP, STL per rod).

    Raises:
        FabricationError: a check failed.
    """
    with start_rod_files([(fab, Path(outdir))], jobs=jobs) as files:
        return files.finish()[0]


def _write_rod(args: tuple[Any, str, str, str, float]) -> tuple[np.ndarray, np.ndarray, float]:
    """One distinct rod's STEP and STL written and checked (:func:`write_rod_files`), in a worker
    or here: (solid on the bed, or its :class:`rodcad.cad.solids.PortableSolid`; STEP path; STL
    path; file stem; plastic volume) -> its mesh (vertices, triangles, deflection) on the bed."""
    from rodcad.cad.export import export_step
    from rodcad.cad.mesh import mesh_solid, write_stl

    solid, step, stl, stem, volume = args
    on_bed = solid.restore() if hasattr(solid, "restore") else solid
    export_step(on_bed, Path(step), stem)
    mesh = mesh_solid(on_bed)
    write_stl(mesh, Path(stl), name=on_bed.label or "rodcad")
    check_files(Path(step), Path(stl), volume)
    return mesh.vertices, mesh.triangles, mesh.deflection


class RodFiles:
    """The rods' files of :func:`start_rod_files`, being written; :meth:`finish` waits for them.
    A context manager: leaving it before :meth:`finish` stops the workers."""

    def __init__(self, chains: Sequence[tuple[ChainFabrication, Path]], jobs: int | None,
                 extra: Sequence[tuple[Any, Path, Path, str, float]] = ()) -> None:
        from rodcad.cad.export import transformed
        from rodcad.cad.solids import PortableSolid
        from rodcad.parallel import default_jobs, worker_pool

        self.chains = [(fab, Path(outdir) / "rods") for fab, outdir in chains]
        self.first: dict[int, tuple[Path, Path, Any]] = {}  # id(solid) -> (STEP, STL, its rod)
        for fab, rods_dir in self.chains:
            rods_dir.mkdir(parents=True, exist_ok=True)
            for r in fab.parts:
                if id(r.solid) not in self.first:
                    self.first[id(r.solid)] = (rods_dir / f"{r.file_stem}.step", rods_dir / f"{r.file_stem}.stl", r)
        self.tasks = [(transformed(r.solid, r.print_matrix), str(step), str(stl), r.file_stem, r.plastic_volume)
                      for step, stl, r in self.first.values()]
        self.tasks += [(solid, str(step), str(stl), name, float(volume)) for solid, step, stl, name, volume in extra]
        jobs = min(default_jobs() if jobs is None else jobs, len(self.tasks))
        self.pool = worker_pool(jobs) if jobs > 1 else None
        self.futures = None
        if self.pool is not None:
            self.futures = [self.pool.submit(_write_rod, (PortableSolid(t[0]), *t[1:])) for t in self.tasks]

    def finish(self) -> list[list[Path]]:
        """Wait for the files, copy them to the rods that share a solid and give each rod its
        mesh; the paths written per chain (STEP, STL per rod).

        Raises:
            FabricationError: a check failed.
        """
        from rodcad.cad.mesh import TriangleMesh

        done = ([f.result() for f in self.futures] if self.futures is not None else
                [_write_rod(t) for t in self.tasks])
        meshes = {key: TriangleMesh(v, t, defl).moved(np.linalg.inv(r.print_matrix))
                  for (key, (_, _, r)), (v, t, defl) in zip(self.first.items(), done)}
        self.close()
        written: list[list[Path]] = []
        for fab, rods_dir in self.chains:
            paths: list[Path] = []
            for r in fab.parts:
                step, stl = rods_dir / f"{r.file_stem}.step", rods_dir / f"{r.file_stem}.stl"
                src = self.first[id(r.solid)]
                if src[0] != step:
                    shutil.copyfile(src[0], step)
                    shutil.copyfile(src[1], stl)
                r.mesh = meshes[id(r.solid)]  # the print files place this mesh, not a second one
                paths += [step, stl]
            written.append(paths)
        return written

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)
            self.pool = None

    def __enter__(self) -> RodFiles:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def start_rod_files(chains: Sequence[tuple[ChainFabrication, Path]], *, jobs: int | None = None,
                    extra: Sequence[tuple[Any, Path, Path, str, float]] = ()) -> RodFiles:
    """Begin writing the rods' files of every (fabrication, folder) as :func:`write_rod_files`
    does: each distinct solid's in a worker process of its own (``jobs``: at most this many;
    None: the CPUs; 1: here, when :meth:`RodFiles.finish` is called), so that the caller writes
    its other files meanwhile. ``extra``: other solids written and checked the same way, as
    they are placed: (solid, STEP path, STL path, name, volume) (a chain's anchor fixture).
    Use it as a context manager and call :meth:`RodFiles.finish`."""
    return RodFiles(chains, jobs, extra)


def write_assembly(fab: ChainFabrication, points: np.ndarray, path: Path, *, name: str = "chain",
                   extra: Sequence[AssemblyPart] = (), pin_diameters: Sequence[float | None] | None = None) -> Path:
    """Write the chain in its simulated pose as a STEP assembly.

    Each rod is a solid named 'NN_TYPE' (its rods/ file stem), placed with its
    frame origin at ``points[i]`` and x along points[i] -> points[i+1] (chain
    plane xy, y up, hinge axes along z), coloured by mass from blue (lightest)
    to red (heaviest); every joint gets a pin 'pin_NN' (pin diameter, through
    the rod thickness), but a fused piece is one solid 'NN-MM_piece' at its first rod, with
    no pins at its fused joints.

    Args:
        fab: the fabricated chain.
        points: (N+1, 2) joint positions (mm).
        path: destination file.
        name: root assembly name.
        extra: further parts (the anchor fixture), placed in the chain plane.
        pin_diameters: (N+1,) each pin's diameter (the joint hardware's; None: the rods').
    """
    pts = np.asarray(points, dtype=float)
    if pts.shape != (len(fab.rods) + 1, 2):
        raise ValueError(f"points must have shape ({len(fab.rods) + 1}, 2), not {pts.shape}")
    fused = {j + 1 for p in fab.pieces for j in range(p.first, p.last)}
    pins = [None if j in fused else (fab.rods[min(j, len(fab.rods) - 1)].pin_diameter
                                     if pin_diameters is None or pin_diameters[j] is None else pin_diameters[j],
                                     fab.rods[min(j, len(fab.rods) - 1)].thickness) for j in range(len(pts))]
    parts = fab.parts
    nodes = chain_parts([r.file_stem for r in parts], [r.solid for r in parts], pts,
                        [r.mass / (getattr(r, "last", r.index) - r.index + 1) for r in parts], pins,
                        at=[r.index for r in parts])
    return export_assembly(path, [*nodes, *extra], name)


def chain_parts(names: Sequence[str], solids: Sequence[Any], points: np.ndarray, masses: Sequence[float],
                pins: Sequence[tuple[float, float] | None], mass_scale: tuple[float, float] | None = None,
                at: Sequence[int] | None = None) -> list[AssemblyPart]:
    """The parts of one chain in its pose: rod i named ``names[i]`` with its rod frame at
    joint p_i and x along p_i -> p_{i+1} (part k at rod ``at[k]`` when given: a fused piece
    at its first rod), coloured by mass (blue light, red heavy; on ``mass_scale`` (lo, hi)
    when given, for one scale over several chains), and a pin 'pin_NN' through every joint,
    ``pins[j] = (diameter, length)`` (mm; None: no pin), centred on the chain plane.
    """
    lo, hi = mass_scale if mass_scale is not None else (None, None)
    colors = mass_colors(masses, lo, hi)
    mats = rod_matrices(points)
    where = range(len(names)) if at is None else at
    parts = [AssemblyPart(name, solid, mats[i], tuple(float(c) for c in col[:3]))
             for name, solid, i, col in zip(names, solids, where, colors)]
    for j, (p, pin) in enumerate(zip(np.asarray(points, dtype=float), pins)):
        if pin is None:
            continue
        diameter, length = pin
        m = np.eye(4)
        m[:2, 3] = p
        m[2, 3] = -length / 2
        parts.append(AssemblyPart(f"pin_{j:02d}", pin_solid(diameter, length), m, (0.75, 0.75, 0.78)))
    return parts
