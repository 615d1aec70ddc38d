"""The 3D view every build writes: ``assembly.glb`` and ``view.html``.

``assembly.glb`` is binary glTF 2.0 (written by trimesh): a root node named after the design
(turning a z-up net or chandelier to glTF's y up), a node per group (``rods``, ``hubs``, ``pins``,
``anchors``, ``supports``: the anchor fixture or frame; a chandelier's chains) and under them a
node per part, named as in design.json and assembly.step (``03_rod-51.764-...``, ``rod-012``,
``hub-007``, ``pin_02``, ``anchor_A``). Parts with one shape and colour share one mesh (glTF
instancing). Lengths are in mm (the asset's ``extras.units``); colours are the rods' masses
on the previews' scale, written linear as glTF asks.

``view.html`` is one self-contained file: the glb (base64), the side panel's numbers (JSON) and
a small WebGL viewer (``viewer.js``, ``viewer.css`` next to this module) inlined, no network at
all. Double-click it: orbit by dragging, pan with the right button (or shift), zoom with the
wheel, F or a double-click fits the view; hovering a part or a table row highlights it and
shows its numbers, clicking keeps it. Without WebGL it draws the triangles on a 2D canvas.
"""

from __future__ import annotations

import base64
import json
from pathlib import Path
from typing import Any

import numpy as np

from rodcad import __version__
from rodcad.outputs.viewgeom import ViewScene

__all__ = ["VIEW_FILES", "scene_glb", "view_html", "view_line", "write_chain_view", "write_chandelier_view",
           "write_net_view", "write_view"]

#: The files the view writes into a build's folder.
VIEW_FILES = ("assembly.glb", "view.html")

_HERE = Path(__file__).resolve().parent


def _linear(c: float) -> float:
    """sRGB -> linear (glTF's baseColorFactor is linear)."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def scene_glb(scene: ViewScene) -> bytes:
    """``scene`` as binary glTF 2.0 (see the module docstring)."""
    import trimesh
    from trimesh.exchange.gltf import export_glb
    from trimesh.visual import TextureVisuals
    from trimesh.visual.material import PBRMaterial

    s = trimesh.Scene()
    names = {p.name for p in scene.parts}
    root = scene.name if scene.name not in names else f"{scene.name} (assembly)"
    s.graph.update(frame_from=s.graph.base_frame, frame_to=root, matrix=np.asarray(scene.up, float))
    colors = {}
    for p in scene.parts:
        colors.setdefault(p.key, p.color)
    for key, mesh in scene.meshes.items():
        rgba = [_linear(float(c)) for c in colors[key]] + [1.0]
        material = PBRMaterial(name=key, baseColorFactor=rgba, metallicFactor=0.0, roughnessFactor=0.6)
        s.geometry[key] = trimesh.Trimesh(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64),
                                          process=False, visual=TextureVisuals(material=material))
    groups: list[str] = []
    for p in scene.parts:
        group = p.group if p.group not in names and p.group != root else f"{p.group} (group)"
        if group not in groups:
            groups.append(group)
            s.graph.update(frame_from=root, frame_to=group, matrix=np.eye(4))
        s.graph.update(frame_from=group, frame_to=p.name, matrix=np.asarray(p.matrix, float), geometry=p.key)

    def tree(t: dict[str, Any]) -> None:
        t["asset"]["generator"] = f"rodcad {__version__}"
        t["asset"]["extras"] = {"units": "mm", "design": scene.name}

    return export_glb(s, include_normals=True, tree_postprocessor=tree)


def _script_json(value: Any) -> str:
    """JSON safe inside a <script> element."""
    return json.dumps(value, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def view_html(glb: bytes, scene: ViewScene) -> str:
    """The self-contained page: the glb, the panel's numbers and the viewer."""
    data = {"panel": scene.panel, "view": scene.view, "generator": f"rodcad {__version__}"}
    css = (_HERE / "viewer.css").read_text(encoding="utf-8")
    js = (_HERE / "viewer.js").read_text(encoding="utf-8")
    title = str(scene.panel.get("title") or scene.name).replace("&", "&amp;").replace("<", "&lt;")
    return (
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{title}: rodcad 3D view</title>"
        f"<style>{css}</style></head><body>\n"
        "<div id=\"app\"><div id=\"view\"><canvas id=\"canvas\"></canvas><div id=\"tip\"></div>"
        "<div id=\"hint\">drag: orbit &middot; right-drag or shift-drag: pan &middot; wheel: zoom &middot; "
        "F or double-click: fit</div><div id=\"mode\"></div></div><aside id=\"side\"></aside></div>\n"
        f"<script id=\"rodcad-data\" type=\"application/json\">{_script_json(data)}</script>\n"
        "<script id=\"rodcad-glb\" type=\"application/octet-stream\">"
        f"{base64.b64encode(glb).decode('ascii')}</script>\n"
        f"<script>{js}</script>\n</body></html>\n")


def _finite(value: Any) -> Any:
    """The panel's numbers with NaN and infinities as None (JSON has neither)."""
    if isinstance(value, float):
        return value if np.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, np.generic):
        return _finite(value.item())
    return value


def write_view(folder: str | Path, scene: ViewScene) -> list[str]:
    """Write ``folder``/assembly.glb and view.html; returns their names."""
    folder = Path(folder)
    scene.panel = _finite(scene.panel)
    glb = scene_glb(scene)
    (folder / "assembly.glb").write_bytes(glb)
    (folder / "view.html").write_text(view_html(glb, scene), encoding="utf-8")
    return list(VIEW_FILES)


def write_chain_view(result, data: dict[str, Any], folder: str | Path) -> list[str]:
    """The view of a built chain (:class:`rodcad.results.BuildResult`, its design.json)."""
    from rodcad.outputs.viewscene import chain_scene

    return write_view(folder, chain_scene(result, data))


def write_chandelier_view(b, data: dict[str, Any], folder: str | Path) -> list[str]:
    """The view of a chandelier (:class:`rodcad.results.ChandelierBuild`, its design.json)."""
    from rodcad.outputs.viewscene import chandelier_scene

    return write_view(folder, chandelier_scene(b, data))


def write_net_view(b, data: dict[str, Any], folder: str | Path) -> list[str]:
    """The view of a net (:class:`rodcad.pipeline.net.NetBuild`, its design.json)."""
    from rodcad.outputs.net.view import net_scene

    return write_view(folder, net_scene(b, data))


def view_line() -> str:
    """The report's line about the view."""
    return ("3D view: open [view.html](view.html) in any browser (double-click it; one file, no network): "
            "drag to orbit, wheel to zoom, hover a part for its numbers. `assembly.glb` is the same scene "
            "for glTF viewers (Blender, online viewers), in mm.")
