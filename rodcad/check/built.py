"""An earlier build, as its design.json records it: what ``rodcad check`` compares against.

:func:`load_built` reads OUTDIR/design.json (a chain built with CAD by ``rodcad build``)
into a :class:`BuiltChain`: the anchors, target and simulated joints, every rod's length,
joint limits and, per fabricated rod, its file, print matrix, as-built mass and centre
of mass and the inserts (metal balls) it holds. Anything that is not such a folder is bad
input, every problem at once, as ``FILE:0:0: key: message`` (JSON has no positions that
matter to a person here; a file that is not JSON gets its line and column).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rodcad.errors import InputError, Problem
from rodcad.outdir import MARKER

__all__ = ["BuiltChain", "BuiltRod", "load_built"]


@dataclass(frozen=True)
class BuiltRod:
    """One fabricated rod as design.json records it (mm, g, rod frame).

    Attributes:
        index: chain position (0-based).
        type: rod type name.
        length: pin to pin (mm).
        designed_mass: the mass the design asked for (g).
        mass: as built: plastic plus balls (g).
        com: as built (along, perp) (mm).
        plastic_volume: printed volume (mm^3).
        ball_centers: (k, 3) ball centres (mm).
        ball_mass: all balls together (g).
        fill_mass: shot poured into a fill chamber (g; 0 without).
        ball_diameter, ball_kind: the balls' diameter (mm) and kind name as recorded (None, '').
        fill_center: (along, perp) where the shot acts (mm): the chamber is centred on the
            rod's centre of mass (:mod:`rodcad.catalog.chamber`), so design.json's as-built
            centre of mass unless its ``fill`` gives a ``center``.
        file: the rod's STEP file (OUTDIR/rods/NN_TYPE.step).
        print_matrix: 4x4 rod frame -> print bed (the file's placement).
        params: the family parameters it was printed with.
        mass_range: [min, max] the design allowed (g).
        pin_diameter: mm; thickness: along the hinge axes (mm).
        piece: (first, last) of the fused piece the rod is printed in (its ``file`` holds the
            whole piece; ``print_matrix`` places this rod's frame in it), or None.
        socket_height: its sockets' flat roofs above the ball centres (mm; 0 where
            design.json does not say: the socket radius; a tuple: one per ball).
        hole_sizes: its pin holes' diameters for its joint hardware (mm; None: the hinge's own).
    """

    index: int
    type: str
    length: float
    designed_mass: float
    mass: float
    com: np.ndarray
    plastic_volume: float
    ball_centers: np.ndarray
    ball_mass: float
    file: Path
    print_matrix: np.ndarray
    params: dict[str, Any]
    mass_range: tuple[float, float]
    pin_diameter: float
    thickness: float
    fill_mass: float = 0.0
    fill_center: np.ndarray | None = None
    ball_diameter: float | None = None
    ball_kind: str = ""
    piece: tuple[int, int] | None = None
    socket_height: float | tuple[float, ...] = 0.0
    hole_sizes: tuple[float | None, float | None] = (None, None)

    @property
    def stem(self) -> str:
        return self.file.stem


@dataclass
class BuiltChain:
    """A chain built with CAD, from its design.json.

    Attributes:
        outdir: the output folder.
        json_path: OUTDIR/design.json.
        data: design.json as read.
        rods: per position.
        anchors: (2, 2); target, simulated: (N+1, 2) joints (mm).
        limits: (N-1, 2) joint limits (rad), +-inf where free.
        density: plastic density (g/mm^3).
        end_limits: (2, 2) the anchor fixture's bounds on the end rods' angles (rad), or None.
    """

    outdir: Path
    json_path: Path
    data: dict[str, Any]
    rods: list[BuiltRod]
    anchors: np.ndarray
    target: np.ndarray
    simulated: np.ndarray
    limits: np.ndarray
    density: float
    end_limits: np.ndarray | None = None

    @property
    def n(self) -> int:
        return len(self.rods)

    @property
    def lengths(self) -> np.ndarray:
        return np.array([r.length for r in self.rods], float)

    @property
    def span(self) -> float:
        return float(np.hypot(*(self.anchors[1] - self.anchors[0])))

    @property
    def catalog(self) -> str:
        return str(self.data.get("catalog") or "")

    def problem(self, key: str, message: str) -> Problem:
        return Problem(str(self.json_path), 0, 0, key, message)


class _Reader:
    """Typed access to design.json that collects a problem per bad key."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.problems: list[Problem] = []

    def bad(self, key: str, message: str) -> None:
        self.problems.append(Problem(str(self.path), 0, 0, key, message))

    def get(self, obj: Any, key: str, where: str, kind: type | tuple[type, ...] = object) -> Any:
        if not isinstance(obj, dict) or key not in obj:
            self.bad(where, "missing (design.json was not written by `rodcad build` with CAD, or was edited)")
            return None
        v = obj[key]
        if not isinstance(v, kind) or isinstance(v, bool) and kind is not bool:
            self.bad(where, f"expected {getattr(kind, '__name__', 'a number')}, got {type(v).__name__}")
            return None
        return v

    def number(self, obj: Any, key: str, where: str, *, positive: bool = False) -> float | None:
        v = self.get(obj, key, where, (int, float))
        if v is None:
            return None
        v = float(v)
        if not math.isfinite(v) or (positive and v <= 0):
            self.bad(where, f"expected a {'positive ' if positive else ''}finite number, got {v!r}")
            return None
        return v

    def array(self, obj: Any, key: str, where: str, shape: tuple[int | None, ...]) -> np.ndarray | None:
        v = self.get(obj, key, where, list)
        if v is None:
            return None
        try:
            a = np.array(v, dtype=float)
        except (TypeError, ValueError):
            self.bad(where, "expected a list of numbers")
            return None
        if a.size == 0 and shape[0] is None and len(shape) == 2:
            a = a.reshape(0, shape[1])
        ok = a.ndim == len(shape) and all(s is None or s == d for s, d in zip(shape, a.shape))
        if not ok or not np.all(np.isfinite(a)):
            want = " x ".join("N" if s is None else str(s) for s in shape)
            self.bad(where, f"expected finite numbers of shape {want}, got shape {a.shape}")
            return None
        return a


def _socket_height(value: Any) -> float | tuple[float, ...]:
    """design.json's ``socket_height_mm``: one number, one per ball, or 0 where absent."""
    if isinstance(value, list) and value and all(isinstance(v, (int, float)) for v in value):
        return tuple(float(v) for v in value)
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else 0.0


def _deg_pair(rd: _Reader, lim: Any, key: str, what: str) -> tuple[float, float] | None:
    """A design.json ``[lo, hi]`` in degrees (null: open on that side) as radians, or None
    (reported) when it is not one."""
    if not isinstance(lim, list) or len(lim) != 2:
        rd.bad(key, f"expected [lo, hi] in degrees (null where {what})")
        return None
    out = [-math.inf, math.inf]
    for k, v in enumerate(lim):
        if v is None:
            continue
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
            rd.bad(f"{key}[{k}]", f"expected a number of degrees or null, got {v!r}")
            continue
        out[k] = math.radians(float(v))
    return out[0], out[1]


def _limits(rd: _Reader, rods: list[Any], n: int) -> np.ndarray:
    out = np.tile([-np.inf, np.inf], (max(n - 1, 0), 1))
    for i in range(n - 1):
        lim = rods[i].get("limits_deg") if isinstance(rods[i], dict) else None
        if lim is not None and (pair := _deg_pair(rd, lim, f"rods[{i}].limits_deg", "free")) is not None:
            out[i] = pair
    return out


def _end_limits(rd: _Reader, data: dict[str, Any]) -> np.ndarray | None:
    """design.json's ``anchor_limits_deg`` (absent or [null, null]: bare pins) in radians."""
    value = data.get("anchor_limits_deg")
    if value is None:
        return None
    out = np.tile([-np.inf, np.inf], (2, 1))
    if not isinstance(value, list) or len(value) != 2:
        rd.bad("anchor_limits_deg", "expected [[lo, hi] | null, [lo, hi] | null] in degrees")
        return None
    for k, lim in enumerate(value):
        if lim is not None and (pair := _deg_pair(rd, lim, f"anchor_limits_deg[{k}]", "open")) is not None:
            out[k] = pair
            if out[k, 0] > out[k, 1]:
                rd.bad(f"anchor_limits_deg[{k}]", "lo is above hi")
    return None if np.all(np.isinf(out)) else out


def _rod(rd: _Reader, outdir: Path, i: int, r: Any) -> BuiltRod | None:
    k = f"rods[{i}]"
    fab = rd.get(r, "fabrication", f"{k}.fabrication", dict)
    if fab is None:
        return None
    name = rd.get(r, "type", f"{k}.type", str)
    length = rd.number(r, "length", f"{k}.length", positive=True)
    designed = rd.number(r, "mass", f"{k}.mass", positive=True)
    params = rd.get(r, "params", f"{k}.params", dict)
    lo_hi = rd.array(r, "mass_range", f"{k}.mass_range", (2,))
    kf = f"{k}.fabrication"
    mass = rd.number(fab, "mass", f"{kf}.mass", positive=True)
    com = rd.array(fab, "com", f"{kf}.com", (2,))
    volume = rd.number(fab, "plastic_volume_mm3", f"{kf}.plastic_volume_mm3", positive=True)
    balls = rd.array(fab, "ball_centers", f"{kf}.ball_centers", (None, 3))
    ball_mass = rd.number(fab, "ball_mass_g", f"{kf}.ball_mass_g")
    file = rd.get(fab, "file", f"{kf}.file", str)
    matrix = rd.array(fab, "print_matrix", f"{kf}.print_matrix", (4, 4))
    if matrix is not None:
        rot = matrix[:3, :3]
        if not (np.allclose(rot @ rot.T, np.eye(3), atol=1e-9) and np.allclose(matrix[3], [0, 0, 0, 1])):
            rd.bad(f"{kf}.print_matrix", "is not a rigid placement (rotation and translation)")
            matrix = None
    path = None
    if file is not None:
        path = (outdir / file)
        if Path(file).is_absolute() or ".." in Path(file).parts or Path(file).suffix.lower() not in (".step", ".stp"):
            rd.bad(f"{kf}.file", f"{file!r} is not a STEP file inside the output folder")
            path = None
    pin = thick = None
    if params is not None:
        pin = rd.number(params, "pin_diameter", f"{k}.params.pin_diameter", positive=True)
        sec = rd.get(params, "section", f"{k}.params.section", dict)
        thick = rd.number(sec, "thickness", f"{k}.params.section.thickness", positive=True) if sec else None
    parts = (name, length, designed, params, lo_hi, mass, com, volume, balls, ball_mass, path, matrix, pin, thick)
    if any(p is None for p in parts):
        return None
    if ball_mass < 0 or (len(balls) == 0 and ball_mass > 1e-9):
        rd.bad(f"{kf}.ball_mass_g", f"{ball_mass} g of balls for {len(balls)} ball centre(s)")
        return None
    fill_mass, fill_center = 0.0, None
    fill = fab.get("fill")
    if fill is not None:  # a fill chamber (shot poured at a print pause)
        grams = rd.number(fill, "grams", f"{kf}.fill.grams")
        center = rd.array(fill, "center", f"{kf}.fill.center", (2,)) if isinstance(fill, dict) and "center" in fill \
            else com
        if grams is None or center is None:
            return None
        fill_mass, fill_center = max(grams, 0.0), center
    piece = fab.get("piece")
    if piece is not None and not (isinstance(piece, list) and len(piece) == 2 and all(
            isinstance(v, int) and not isinstance(v, bool) for v in piece) and piece[0] <= i <= piece[1]):
        rd.bad(f"{kf}.piece", f"expected [first, last] rod indices around {i}, got {piece!r}")
        return None
    return BuiltRod(i, name, length, designed, mass, com, volume, balls, max(ball_mass, 0.0), path, matrix, params,
                    (float(lo_hi[0]), float(lo_hi[1])), pin, thick, fill_mass, fill_center,
                    float(fab["ball_diameter_mm"]) if isinstance(fab.get("ball_diameter_mm"), (int, float)) else None,
                    str(fab.get("ball_kind") or ""), None if piece is None else (piece[0], piece[1]),
                    _socket_height(fab.get("socket_height_mm")), _hole_sizes(r))


def _hole_sizes(r: Any) -> tuple[float | None, float | None]:
    """The rod's pin holes' diameters for its joint hardware (design.json ``rods[].hardware.
    holes_mm``), or (None, None): the hinge's own (an older build, or no hardware)."""
    hw = r.get("hardware") if isinstance(r, dict) else None
    holes = hw.get("holes_mm") if isinstance(hw, dict) else None
    if isinstance(holes, list) and len(holes) == 2 and all(isinstance(v, (int, float)) and v > 0 for v in holes):
        return float(holes[0]), float(holes[1])
    return None, None


def _folder_problems(outdir: Path) -> list[Problem]:
    raw = str(outdir)
    if not outdir.exists():
        return [Problem(raw, 0, 0, "OUTDIR", "no such folder")]
    if not outdir.is_dir():
        return [Problem(raw, 0, 0, "OUTDIR", "is not a folder; give the output folder of `rodcad build`")]
    js = outdir / "design.json"
    if not js.is_file():
        return [Problem(raw, 0, 0, "OUTDIR", "has no design.json: not an output folder of `rodcad build`")]
    if not (outdir / MARKER).is_file():
        return [Problem(raw, 0, 0, "OUTDIR", f"has no {MARKER} marker: not an output folder written by "
                        "`rodcad build`")]
    return []


def load_built(outdir: str | Path) -> BuiltChain:
    """Read an output folder of ``rodcad build`` (built with CAD).

    Raises:
        InputError: not such a folder, design.json unreadable, a chandelier, a build without
            CAD, or a key missing or malformed (every problem found).
    """
    out = Path(outdir)
    problems = _folder_problems(out)
    if problems:
        raise InputError(problems)
    path = out / "design.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as err:
        raise InputError([Problem(str(path), err.lineno, err.colno, "", f"is not valid JSON: {err.msg}")]) from None
    except (OSError, UnicodeDecodeError) as err:
        raise InputError([Problem(str(path), 0, 0, "", f"cannot be read: {err}")]) from None
    rd = _Reader(path)
    if not isinstance(data, dict) or "rodcad" not in data:
        raise InputError([Problem(str(path), 0, 0, "", "was not written by `rodcad build` (no 'rodcad' key)")])
    if "chains" in data:
        raise InputError([Problem(str(path), 0, 0, "chains", "a chandelier: `rodcad check` re-reads single "
                                  "chains only (check each chain's rods by building it as its own design)")])
    rods = rd.get(data, "rods", "rods", list)
    if rods is not None and not rods:
        rd.bad("rods", "no rods")
    if rods and not any(isinstance(r, dict) and "fabrication" in r for r in rods):
        raise InputError([Problem(str(path), 0, 0, "rods", "was built without CAD (`--no-cad`): there are no rod "
                                  "files to re-read; build with CAD first")])
    anchors = rd.array(data, "anchors", "anchors", (2, 2))
    n = len(rods) if rods else 0
    target = rd.array(data.get("target"), "points", "target.points", (n + 1, 2))
    simulated = rd.array(data.get("simulated"), "points", "simulated.points", (n + 1, 2))
    prof = rd.get(data, "print", "print", dict)
    density = rd.number(prof, "density", "print.density", positive=True) if prof is not None else None
    built = [_rod(rd, out, i, r) for i, r in enumerate(rods or [])]
    limits = _limits(rd, rods or [], n)
    end_limits = _end_limits(rd, data)
    if rd.problems:
        raise InputError(rd.problems)
    assert anchors is not None and target is not None and simulated is not None and density is not None
    return BuiltChain(out, path, data, [r for r in built if r is not None], anchors, target, simulated, limits,
                      density / 1000.0, end_limits)
