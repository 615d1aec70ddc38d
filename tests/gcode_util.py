"""PrusaSlicer from the tests: slice a 3MF project, read its G-code (pauses, extrusion by
feature type, per layer and object). Shared by tests/test_printfile.py and
tests/test_netprint.py."""

from __future__ import annotations

import dataclasses
import math
import re
import shutil
import subprocess
from pathlib import Path

import pytest

PRUSA = shutil.which("prusa-slicer")
needs_slicer = pytest.mark.skipif(PRUSA is None, reason="prusa-slicer is not on PATH (Debian: apt-get install "
                                                          "prusa-slicer): the G-code checks need the slicer")


#: Extrusion types (PrusaSlicer's ``;TYPE:``) that are not part of any rod.
NOT_ROD = ("Skirt/Brim", "Support material", "Support material interface", "Wipe tower")


def slice_file(src: Path, gcode: Path, *extra: str) -> str:
    run = subprocess.run([PRUSA, "--dont-arrange", *extra, "--export-gcode", str(src), "--output", str(gcode)],
                         capture_output=True, text=True, timeout=300)
    said = [line for line in (run.stdout + run.stderr).splitlines() if "[trace]" not in line]
    assert run.returncode == 0 and gcode.exists(), f"{src.name}: " + "\n".join(said[-20:])
    errors = [line for line in said if re.search(r"error|warning", line, re.I)]
    assert errors == [], f"{src.name}: {errors}"
    return gcode.read_text()


@dataclasses.dataclass
class Sliced:
    """What a G-code says, read from PrusaSlicer's comments and moves.

    Attributes:
        pauses: (print_z, message) per M601, the message of the M117 just before it.
        types: {(print_z, object): extrusion types printed in that layer of that object}.
        filament: {extrusion type: filament (mm) it extrudes}.
        early: print_z of every M601 that came after an extrusion of its layer.
        objects: {object: {extrusion type: filament (mm)}} ('' outside any object).
    """

    pauses: list[tuple[float, str]]
    types: dict[tuple[float, str], set[str]]
    filament: dict[str, float]
    early: list[float]
    objects: dict[str, dict[str, float]] = dataclasses.field(default_factory=dict)

    def grams(self, diameter: float, density: float, *, skip: tuple[str, ...] = ()) -> float:
        return self.object_grams(None, diameter, density, skip=skip)

    def object_grams(self, obj: str | None, diameter: float, density: float, *,
                     skip: tuple[str, ...] = ()) -> float:
        """Grams of filament one object (None: all) extrudes, leaving out the types ``skip``."""
        by_type = self.filament if obj is None else self.objects.get(obj, {})
        mm = sum(v for k, v in by_type.items() if k not in skip)
        return mm * math.pi * diameter**2 / 4 * density / 1000


def read_gcode(gcode: str) -> Sliced:
    """Layers (``;Z:``), objects (``; printing object``), types (``;TYPE:``), pauses (M117 +
    M601) and the filament of every extruding move (absolute or relative E, G92 resets;
    retractions and the E-only moves that undo them are left out)."""
    z, obj, kind, message = 0.0, "", "", ""
    absolute, e = True, 0.0
    out = Sliced([], {}, {}, [])
    extruded = False
    for line in gcode.splitlines():
        if line.startswith(";Z:"):
            z, extruded = float(line[3:]), False
            continue
        if line.startswith("; printing object "):
            obj = line.split()[3]
            continue
        if line.startswith("; stop printing object"):
            obj = ""
            continue
        if line.startswith(";TYPE:"):
            kind = line[6:]
            out.types.setdefault((z, obj), set()).add(kind)
            continue
        words = line.split(";")[0].split()
        if not words:
            continue
        code, args = words[0], {w[0]: w[1:] for w in words[1:] if w}
        if code == "M117":
            message = line.split(";")[0][5:].strip()
        elif code == "M601":
            out.pauses.append((z, message))
            if extruded:
                out.early.append(z)
        elif code == "M82":
            absolute = True
        elif code == "M83":
            absolute = False
        elif code == "G92" and "E" in args:
            e = float(args["E"])
        elif code in ("G0", "G1", "G2", "G3") and "E" in args:
            v = float(args["E"])
            d = v - e if absolute else v
            e = v if absolute else e
            if d > 0 and ("X" in args or "Y" in args):
                out.filament[kind] = out.filament.get(kind, 0.0) + d
                per = out.objects.setdefault(obj, {})
                per[kind] = per.get(kind, 0.0) + d
                extruded = True
    return out


def travel_moves(gcode: str) -> list[tuple[float, tuple[float, float], tuple[float, float], int]]:
    """Every move without extrusion in x/y: (print_z, from (x, y), to (x, y), pauses before it);
    absolute x/y as PrusaSlicer writes them. The nozzle's height on a travel is the layer's
    print_z plus any z lift (the projects rodcad writes lift none)."""
    z, x, y, paused = 0.0, None, None, 0
    out = []
    for line in gcode.splitlines():
        if line.startswith(";Z:"):
            z = float(line[3:])
            continue
        words = line.split(";")[0].split()
        if not words:
            continue
        if words[0] == "M601":
            paused += 1
            continue
        if words[0] not in ("G0", "G1"):
            continue
        args = {w[0]: float(w[1:]) for w in words[1:] if w and w[0] in "XYZE"}
        nx, ny = args.get("X", x), args.get("Y", y)
        if ("X" in args or "Y" in args) and x is not None and args.get("E", 0.0) <= 0:
            out.append((z, (x, y), (nx, ny), paused))
        x, y = nx, ny
    return out


def model_vertices(project: Path) -> dict[str, "list[tuple[float, float, float]]"]:
    """{object name: its mesh's vertices} of a 3MF project whose build items carry no
    transform (rodcad's: the vertices already where they print, mm)."""
    import zipfile

    with zipfile.ZipFile(project) as z:
        xml = z.read("3D/3dmodel.model").decode()
    out = {}
    for m in re.finditer(r'<object id="\d+" name="([^"]+)".*?</object>', xml, re.S):
        out[m.group(1)] = [tuple(float(v) for v in t) for t in
                           re.findall(r'<vertex x="([^"]+)" y="([^"]+)" z="([^"]+)"', m.group(0))]
    return out
