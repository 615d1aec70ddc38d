"""A net's distinct parts: rods and hubs that are the same solid, found from what they are built
from, built once and confirmed on the exact B-rep.

Identity. A rod is built from its hardware (every field of the
:class:`rodcad.catalog.net.node.NodeHardware` it is made with), its length, its steel balls,
its cavity and, bent, its arc (:class:`rodcad.catalog.net.bend.NetRodArc`); a hub from its
hardware (the one it is cut with: its own size, socket clearance, cone) and its sockets'
centres. Two parts are candidates for one solid when every discrete parameter is equal and
every number agrees within :data:`TOL_MM` (the cavity as the length of bore it takes); a hub's
sockets must coincide, within :data:`TOL_MM`, after a rotation of the hub (the rotation is
kept: the member hangs as the shared solid turned by it). A mirror image is not a rotation, so
it stays a part of its own.

Confirmation. Each group's task builds the first member's solid (the one written) and every
other member's bare solid (a hub before it is cut in halves), and compares their volumes and
principal moments of inertia (OCC's integration to 1e-9, :func:`signature`): within
:data:`REL_TOL` the member shares the part, else it is built as a part of its own. Masses and
centres of mass of every member are its own B-rep's.

Tasks. :func:`rodcad.cad.net.build.build_group` is a pure function of a :class:`PartTask` (numbers in, BREP and
checked STEP/STL bytes and numbers out): it runs in this process, in worker processes or on a
Dask cluster (:func:`rodcad.parallel.task_runner`) with the same result.

Units: mm.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["REL_TOL", "TOL_MM", "HubSpec", "PartGroup", "PartResult", "PartTask", "RodSpec", "brep_bytes",
           "from_brep", "group_parts", "signature", "socket_rotation"]

#: Numbers a part is built from agree within this (mm): ten times OCC's confusion tolerance
#: (1e-7 mm), far under anything a printer makes; symmetric rods' and hubs' numbers agree to
#: about 1e-12 mm (round-off), different ones differ by 1e-3 mm or more.
TOL_MM = 1e-6
#: Volumes and principal moments of inertia of one part's members agree within this share:
#: parameters within TOL_MM move them by about 1e-8, OCC integrates them to 1e-9.
REL_TOL = 1e-6


@dataclass(frozen=True)
class RodSpec:
    """What a net rod is built from (:func:`rodcad.cad.net.solids.net_rod_solid`,
    :func:`rodcad.cad.net.bent.bent_rod_solid`)."""

    hardware: object
    length: float
    balls: int
    cavity: float
    arc: object = None
    fills: tuple = ()  # a spliced rod's, per piece (balls, cavity mm^3) (:mod:`rodcad.cad.net.splice`)

    @property
    def pieces(self) -> int:
        return max(len(self.fills), 1)


@dataclass(frozen=True)
class HubSpec:
    """What a hub is built from: the hardware it is cut with and its sockets' centres
    ((k, 3), hub frame, mm)."""

    hardware: object
    sockets: tuple


def _flat(obj, out_d: list, out_n: list) -> None:
    """Every field of ``obj`` (dataclasses, sequences, arrays, scalars), in order: numbers to
    ``out_n``, anything else (names, counts, flags) to ``out_d``."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        out_d.append(type(obj).__name__)
        for f in dataclasses.fields(obj):
            out_d.append(f.name)
            _flat(getattr(obj, f.name), out_d, out_n)
    elif isinstance(obj, (list, tuple, np.ndarray)):
        seq = list(np.asarray(obj).reshape(-1)) if isinstance(obj, np.ndarray) else list(obj)
        out_d.append(len(seq))
        for v in seq:
            _flat(v, out_d, out_n)
    elif isinstance(obj, (bool, np.bool_, int, np.integer, str)) or obj is None:
        out_d.append(obj.item() if isinstance(obj, np.generic) else obj)
    elif isinstance(obj, (float, np.floating)):
        out_n.append(float(obj))
    else:
        out_d.append(repr(obj))


def _key(spec) -> tuple[tuple, np.ndarray]:
    """(discrete parameters, numbers in mm) of a part spec; a hub's sockets are compared apart."""
    d: list = [type(spec).__name__]
    n: list = []
    _flat(spec.hardware, d, n)
    if isinstance(spec, RodSpec):
        hw = spec.hardware
        bore = math.pi * max(hw.rod_diameter / 2 - hw.min_wall, 1e-9) ** 2
        d += [int(spec.balls), spec.arc is None, spec.pieces] + [int(b) for b, _ in spec.fills]
        n += [float(spec.length), float(spec.cavity) / bore] + [float(c) / bore for _, c in spec.fills]
        if spec.arc is not None:
            _flat(spec.arc, d, n)
    else:
        d.append(len(spec.sockets))
    return tuple(d), np.asarray(n, float)


def _frame(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """3 x 3, columns: u's direction, v's part across u, their normal."""
    a = u / np.linalg.norm(u)
    w = v - (v @ a) * a
    w = w / np.linalg.norm(w)
    return np.column_stack([a, w, np.cross(a, w)])


def _turn(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The smallest rotation taking direction u to direction v."""
    a, b = u / np.linalg.norm(u), v / np.linalg.norm(v)
    c, axis = float(a @ b), np.cross(a, b)
    s = float(np.linalg.norm(axis))
    if s < 1e-12:
        if c > 0:
            return np.eye(3)
        p = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
        p /= np.linalg.norm(p)
        return 2 * np.outer(p, p) - np.eye(3)  # a half turn about p
    k = axis / s
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * K + (1 - c) * K @ K


def socket_rotation(a: np.ndarray, b: np.ndarray, tol: float = TOL_MM) -> np.ndarray | None:
    """A rotation R (3 x 3, det +1) with R @ a[i] = b[p(i)] within ``tol`` mm for a permutation p,
    or None: the hub with sockets ``a`` turned by R is the hub with sockets ``b``."""
    a, b = np.asarray(a, float).reshape(-1, 3), np.asarray(b, float).reshape(-1, 3)
    if len(a) != len(b):
        return None
    if not len(a):
        return np.eye(3)
    if np.max(np.abs(np.sort(np.linalg.norm(a, axis=1)) - np.sort(np.linalg.norm(b, axis=1)))) > tol:
        return None

    def fits(R: np.ndarray) -> bool:
        d = np.linalg.norm((a @ R.T)[:, None, :] - b[None, :, :], axis=2)
        near = d.argmin(axis=1)
        return bool(np.all(d[np.arange(len(a)), near] <= tol) and len(set(near.tolist())) == len(a))

    na = np.linalg.norm(a, axis=1)
    i0 = int(np.argmax(na))
    cross = np.linalg.norm(np.cross(a[i0], a), axis=1)
    i1 = int(np.argmax(cross))
    nb = np.linalg.norm(b, axis=1)
    for j0 in np.flatnonzero(np.abs(nb - na[i0]) <= tol):
        if cross[i1] <= 1e-9 * na[i0] * max(na[i1], 1e-9):  # every socket on one line through the centre
            R = _turn(a[i0], b[j0])
            if fits(R):
                return R
            continue
        for j1 in np.flatnonzero(np.abs(nb - na[i1]) <= tol):
            if j1 == j0 or abs(np.linalg.norm(b[j0] - b[j1]) - np.linalg.norm(a[i0] - a[i1])) > 2 * tol:
                continue
            R = _frame(b[j0], b[j1]) @ _frame(a[i0], a[i1]).T
            if fits(R):
                return R
    return None


@dataclass
class PartGroup:
    """Parts found to be one solid (:func:`group_parts`).

    Attributes:
        members: the parts' indices (in the order given), the first the one built and written.
        rotations: per member, R (3 x 3): the member is the first member's solid turned by R
            (the identity for rods and for the first member).
    """

    members: list[int]
    rotations: list[np.ndarray]


def group_parts(specs, tol: float = TOL_MM) -> list[PartGroup]:
    """Parts with equal construction parameters (module docstring) grouped, in the order of
    their first member; deterministic."""
    groups: list[PartGroup] = []
    by_key: dict[tuple, list[tuple[int, np.ndarray]]] = {}
    for i, spec in enumerate(specs):
        d, n = _key(spec)
        placed = False
        for g, n0 in by_key.get(d, []):
            if n0.shape != n.shape or (n.size and np.max(np.abs(n0 - n)) > tol):
                continue
            first = specs[groups[g].members[0]]
            R = socket_rotation(first.sockets, spec.sockets, tol) if isinstance(spec, HubSpec) else np.eye(3)
            if R is not None:
                groups[g].members.append(i)
                groups[g].rotations.append(R)
                placed = True
                break
        if not placed:
            by_key.setdefault(d, []).append((len(groups), n))
            groups.append(PartGroup([i], [np.eye(3)]))
    return groups


def signature(solid) -> np.ndarray:
    """(volume mm^3, principal moments of inertia, sorted, mm^5) of a solid by OCC's
    integration to a relative 1e-9: equal for a solid and any rotated copy."""
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid.wrapped, props, 1e-9, True)
    m = props.MatrixOfInertia()
    inertia = np.array([[m.Value(i, j) for j in (1, 2, 3)] for i in (1, 2, 3)])
    return np.concatenate([[props.Mass()], np.sort(np.linalg.eigvalsh(inertia))])


def brep_bytes(solid) -> bytes:
    """The solid in OCC's BREP format (exact: every number at full precision)."""
    from OCP.BRepTools import BRepTools

    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "part.brep")
        BRepTools.Write_s(solid.wrapped, path)
        return Path(path).read_bytes()


def from_brep(data: bytes, label: str = ""):
    """A build123d Solid from :func:`brep_bytes` (its label set)."""
    from build123d import Solid
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Shape

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "part.brep"
        path.write_bytes(data)
        shape = TopoDS_Shape()
        BRepTools.Read_s(shape, str(path), BRep_Builder())
    s = Solid(shape)
    s.label = label
    return s


@dataclass
class PartTask:
    """One group's work: its members' specs (the first built and written) and names.

    Attributes:
        kind: 'rod' or 'hub'.
        specs: per member, its :class:`RodSpec` or :class:`HubSpec`.
        label: the written part's name ('rod-003', 'hub-012').
        deflection: (linear mm, angular rad) of its STL (:func:`rodcad.cad.mesh.print_deflection`).
    """

    kind: str
    specs: list
    label: str
    deflection: tuple[float, float]


@dataclass
class PartResult:
    """What :func:`build_group` returns (plain bytes and numbers: it travels between processes).

    Attributes:
        solids: per printed solid (a rod; a hub, or its halves 'a' and 'b'), (label, BREP bytes).
        files: per printed solid, {'.step': bytes, '.stl': bytes}, each checked.
        print_matrices: per printed solid, its 4 x 4 onto the bed (hub halves; identity else).
        split_reason: why a hub is printed whole ('' when cut in halves or a rod).
        off_plane, normal, offset: the hub's cut plane (:class:`rodcad.cad.net.hub.HubSplit`).
        volumes: per member, its own solid's volume (mm^3); com: (members, 3) its centre of mass
            in its own frame (mm).
        confirmed: per member, its B-rep's signature matched the first member's.
        mesh_volumes: per printed solid, its STL's volume (mm^3).
        whole: a hub cut in halves or a spliced rod, the whole part's BREP (b'' else).
        copies: per printed solid, how many each member needs (empty: one each; a spliced rod's
            end piece two, the same solid turned end for end).
    """

    solids: list[tuple[str, bytes]]
    files: list[dict[str, bytes]]
    print_matrices: list[np.ndarray]
    volumes: list[float]
    com: np.ndarray
    confirmed: list[bool]
    mesh_volumes: list[float] = field(default_factory=list)
    split_reason: str = ""
    off_plane: float = 0.0
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    offset: float = 0.0
    whole: bytes = b""
    copies: list[int] = field(default_factory=list)
