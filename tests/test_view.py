"""The 3D view every build writes (rodcad.outputs.view): assembly.glb read back by trimesh (a
node per rod, hub, pin and anchor, named as in design.json; colours by mass; sizes in mm; the
solids' meshes with CAD), view.html self-contained (no URL a browser would load, the glb
embedded) and drawn by headless Chromium: the screenshot shows the structure in the rods'
colours inside the view, the side panel beside it, with WebGL and with the 2D fallback.

The builds are the session's (tests/conftest.py BuildStore: tests/test_build.py and
test_preview.py read the same semicircle and chandelier, test_asprinted.py and
test_build_cad.py the semicircle with CAD); only the lampshade is built for this module.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from expected_exits import EXPECTED_EXIT, built_folder
from rodcad.colors import mass_colors
from rodcad.outputs.viewgeom import Y_UP

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: The window of the screenshots, and the side panel's width in it (viewer.css).
WINDOW, PANEL = (1000, 700), 380


@pytest.fixture(scope="module")
def semicircle(build_store) -> Path:
    code, out, _ = build_store.cli_build(EXAMPLES / "semicircle.yaml", "--no-cad", "-q")
    assert code == 0
    return out


@pytest.fixture(scope="module")
def chandelier(build_store) -> Path:
    code, out, _ = build_store.cli_build(EXAMPLES / "chandelier.yaml", "--no-cad", "-q")
    assert code == 0
    return out


@pytest.fixture(scope="module")
def lampshade(build_store) -> Path:
    code, out, _ = build_store.cli_build(EXAMPLES / "lampshade.yaml", "--no-cad", "-q")
    assert code == 0
    return out


@pytest.fixture(scope="module")
def semicircle_cad(build_store) -> Path:
    code, out, _ = build_store.cli_build(EXAMPLES / "semicircle.yaml", "--jobs", "2", "-q")
    assert code == 0
    return out


def _scene(out: Path):
    import trimesh

    return trimesh.load(out / "assembly.glb", force="scene")


def _srgb(c: np.ndarray) -> np.ndarray:
    c = np.asarray(c, float)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def _color(scene, node: str) -> np.ndarray:
    """The sRGB colour of a node's material (glTF writes it linear)."""
    _, geom = scene.graph[node]
    return _srgb(np.asarray(scene.geometry[geom].visual.material.baseColorFactor[:3], float) / 255.0)


def _group(scene, node: str) -> str:
    return scene.graph.transforms.parents[node]


def _world_vertices(scene, node: str) -> np.ndarray:
    """A node's vertices in the design's frame (mm): the glb's y-up undone."""
    matrix, geom = scene.graph[node]
    v = np.asarray(scene.geometry[geom].vertices, float)
    up = scene.graph[_group(scene, _group(scene, node))][0]  # the root: design frame -> y up
    m = np.linalg.inv(up) @ matrix
    return v @ m[:3, :3].T + m[:3, 3]


def _check_mass_colors(scene, names: list[str], masses: list[float]) -> None:
    """Every rod in the previews' colour of its mass (to a step of the scale and 8 bits): read
    back on the scale, the colours rise with the masses, the heaviest rod at its red end and
    the lightest at its blue end."""
    got = np.array([_color(scene, n) for n in names])
    m = np.asarray(masses, float)
    np.testing.assert_allclose(got, mass_colors(m)[:, :3], atol=0.03)
    lo, hi = m.min(), m.max()
    scale = mass_colors(np.linspace(lo, hi, 1001), lo, hi)[:, :3]
    t = np.argmin(np.linalg.norm(got[:, None, :] - scale[None], axis=2), axis=1) / 1000  # where on the scale
    assert t[np.argmax(m)] > 0.98 and t[np.argmin(m)] < 0.02
    order = np.argsort(m)
    assert np.all(np.diff(t[order]) >= -0.02)  # up the scale with the mass, to a step of it


def test_a_chain_has_a_node_per_rod_pin_and_anchor_in_mm(semicircle):
    data = json.loads((semicircle / "design.json").read_text())
    scene = _scene(semicircle)
    rods = [f"{r['index']:02d}_{r['type']}" for r in data["rods"]]
    n = len(rods)
    parts = set(scene.graph.nodes_geometry)
    assert parts == {*rods, *(f"pin_{j:02d}" for j in range(1, n)), "anchor_A", "anchor_B"}
    assert {_group(scene, r) for r in rods} == {"rods"} and _group(scene, "anchor_A") == "anchors"
    _check_mass_colors(scene, rods, [r["mass"] for r in data["rods"]])
    points = np.array(data["simulated"]["points"])
    for i, (name, rod) in enumerate(zip(rods, data["rods"])):
        v = _world_vertices(scene, name)
        lo, hi = v.min(axis=0), v.max(axis=0)
        height = rod["params"]["body"]["height"]
        for p in points[i:i + 2]:  # both joints inside the rod, which is no longer than it and its ends
            assert np.all(lo[:2] < p) and np.all(p < hi[:2])
        assert np.hypot(*(hi - lo)[:2]) < rod["length"] + 1.5 * height
        assert hi[2] - lo[2] == pytest.approx(rod["params"]["body"]["thickness"], rel=0.11)
    # identical rods share one mesh (glTF instancing)
    assert len({scene.graph[r][1] for r in rods}) == len({(r["type"], r["index"] % 2) for r in data["rods"]})


def test_a_net_has_a_node_per_rod_and_hub_in_mm_and_z_up_as_y_up(lampshade):
    data = json.loads((lampshade / "design.json").read_text())
    net = data["net"]
    scene = _scene(lampshade)
    rods = [f"rod-{r['index']:03d}" for r in net["rods"]]
    hubs = [f"hub-{nd['index']:03d}" for nd in net["nodes"]]
    anchors = [f"anchor-{nd['index']:03d}" for nd in net["nodes"] if nd["anchored"]]
    assert set(scene.graph.nodes_geometry) == {*rods, *hubs, *anchors}
    assert len(anchors) == 12 and {_group(scene, h) for h in hubs} == {"hubs"}
    _check_mass_colors(scene, rods, [r["mass"] for r in net["rods"]])
    for nd, h in zip(net["nodes"], hubs):  # the hub at its node: y up in the glb
        world = scene.graph[h][0]
        np.testing.assert_allclose(world[:3, 3], Y_UP[:3, :3] @ nd["simulated"], atol=1e-6)
        v = _world_vertices(scene, h)
        assert np.ptp(v, axis=0) == pytest.approx([data["hardware"]["diameter"]] * 3, rel=0.03)
    for r, name in zip(net["rods"], rods):  # a cylinder from pivot to pivot
        v = _world_vertices(scene, name)
        a, b = np.array(r["ends"])
        axis = (b - a) / np.linalg.norm(b - a)
        along = (v - a) @ axis
        assert along.min() == pytest.approx(0, abs=1e-6) and along.max() == pytest.approx(r["length"], rel=1e-6)
        radial = np.linalg.norm((v - a) - np.outer(along, axis), axis=1)
        assert radial.max() == pytest.approx(r["diameter"] / 2, rel=1e-6)
    # the straight rods are one unit cylinder per colour, scaled by their nodes
    assert len({scene.graph[r][1] for r in rods}) <= len({tuple(_color(scene, r).round(3)) for r in rods})


def test_a_chandelier_has_every_chain_and_its_frame(chandelier):
    data = json.loads((chandelier / "design.json").read_text())
    scene = _scene(chandelier)
    rods = [f"{c['name']}.{r['index']:02d}_{r['type']}" for c in data["chains"] for r in c["rods"]]
    parts = set(scene.graph.nodes_geometry)
    assert set(rods) <= parts and "frame" in parts and len(rods) == 72
    assert {_group(scene, r) for r in rods} == {c["name"] for c in data["chains"]}
    _check_mass_colors(scene, rods, [r["mass"] for c in data["chains"] for r in c["rods"]])
    for c in data["chains"]:  # each chain hangs from its anchors' lugs
        for k, name in ((0, "anchor_A"), (1, "anchor_B")):
            centre = _world_vertices(scene, f"{c['name']}.{name}").mean(axis=0)
            assert np.linalg.norm(centre - c["anchors_3d"][k]) < 1e-6


def test_with_cad_the_view_shows_the_solids(semicircle_cad):
    """The rods' and pins' solids as assembly.step places them (their names), the anchor
    fixture, coarse meshes of real solids (not the simple shapes), equal pins meshed once."""
    data = json.loads((semicircle_cad / "design.json").read_text())
    scene = _scene(semicircle_cad)
    rods = [f"{r['index']:02d}_{r['type']}" for r in data["rods"]]
    parts = set(scene.graph.nodes_geometry)
    assert {*rods, "fixture", "anchor_A", "anchor_B"} <= parts
    pins = sorted(p for p in parts if p.startswith("pin_"))
    assert pins == [f"pin_{j:02d}" for j in range(1, len(rods))]
    assert len({scene.graph[p][1] for p in pins}) < len(pins)  # equal pins: one mesh
    _check_mass_colors(scene, rods, [r["mass"] for r in data["rods"]])
    points = np.array(data["as_built"]["points"])  # where it hangs as built
    for i, name in enumerate(rods):
        v = _world_vertices(scene, name)
        assert len(v) > 200  # a meshed solid: knuckles, holes, chamfers
        for p in points[i:i + 2]:
            assert np.all(v.min(axis=0)[:2] < p) and np.all(p < v.max(axis=0)[:2])
    size = (semicircle_cad / "assembly.glb").stat().st_size
    assert size < 1_000_000, size


@pytest.mark.parametrize("build", ["semicircle", "lampshade", "chandelier", "semicircle_cad"])
def test_view_html_is_one_self_contained_file(build, request):
    out = request.getfixturevalue(build)
    html = (out / "view.html").read_text(encoding="utf-8")
    assert not re.search(r"(?i)https?:|//[a-z0-9.-]+\.[a-z]{2,}/", html)  # no URL at all
    assert not re.search(r"(?i)<(script|link|img|iframe|source|object|embed)\b[^>]*\b(src|href|data)\s*=", html)
    assert not re.search(r"(?i)@import|url\(|\bfetch\(|XMLHttpRequest|import\(", html)
    glb = re.search(r'<script id="rodcad-glb" type="application/octet-stream">([^<]*)</script>', html).group(1)
    assert base64.b64decode(glb) == (out / "assembly.glb").read_bytes()
    panel = json.loads(re.search(r'<script id="rodcad-data" type="application/json">([^<]*)</script>', html)
                       .group(1))["panel"]
    data = json.loads((out / "design.json").read_text())
    assert panel["title"] == data["name"]
    rods = data["net"]["rods"] if "net" in data else [r for c in data.get("chains", [data]) for r in c["rods"]]
    assert len(panel["tables"][-2 if "net" in data else -1 if "chains" in data else 0]["rows"]) == len(rods)
    assert len(html) < 4 / 3 * (out / "assembly.glb").stat().st_size + 200_000  # the glb and 200 kB
    report = (out / "report.md").read_text()
    assert "[view.html](view.html)" in report and "assembly.glb" in report


# --------------------------------------------------------------------------- headless Chromium


def _browser() -> str | None:
    return next((path for path in map(shutil.which, BROWSERS) if path), None)


def _chromium(page: Path, tmp_path: Path, *flags: str) -> subprocess.CompletedProcess:
    """Headless Chromium on ``page`` (its own profile, a time limit on everything)."""
    browser = _browser()
    if browser is None:
        pytest.skip("no chromium, chromium-browser or google-chrome on PATH (apt-get install chromium)")
    cmd = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
           f"--user-data-dir={tmp_path / 'profile'}", f"--window-size={WINDOW[0]},{WINDOW[1]}",
           "--virtual-time-budget=5000", "--hide-scrollbars", *flags, page.resolve().as_uri()]
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=90, check=False)
    except subprocess.TimeoutExpired:
        pytest.fail(f"{browser} did not finish drawing {page} in 90 s")


def _screenshot(out: Path, tmp_path: Path, *flags: str) -> np.ndarray:
    from PIL import Image

    png = tmp_path / "view.png"
    done = _chromium(out / "view.html", tmp_path, f"--screenshot={png}", *flags)
    assert png.is_file(), done.stderr[-2000:]
    image = np.asarray(Image.open(png).convert("RGB"), float)
    assert image.shape[:2] == (WINDOW[1], WINDOW[0])
    return image


def _check_screenshot(image: np.ndarray) -> None:
    """The structure drawn in the view, in the rods' colours (the scale's red and blue ends:
    every build has a lightest and a heaviest rod), framed inside it; the panel beside it."""
    view, panel = image[:-28, :WINDOW[0] - PANEL], image[:, WINDOW[0] - PANEL + 10:]  # the view above its hints
    assert view.std() > 12, "the view is blank"
    r, g, b = view[..., 0], view[..., 1], view[..., 2]
    red = (r - b > 60) & (r > 120)
    blue = (b - r > 60) & (b > 110)
    assert red.sum() > 300 and blue.sum() > 300, (int(red.sum()), int(blue.sum()))
    drawn = (red | blue | (np.abs(r - b) + np.abs(g - b) > 40) | (view.max(axis=2) < 150))
    ys, xs = np.nonzero(drawn)
    assert xs.min() > 3 and ys.min() > 3 and xs.max() < view.shape[1] - 4 and ys.max() < view.shape[0] - 3
    assert max((xs.max() - xs.min()) / view.shape[1], (ys.max() - ys.min()) / view.shape[0]) > 0.5  # fills it
    assert (panel.max(axis=2) < 110).sum() > 2000  # the panel's text


#: Every example a build can take (chain.yaml is for ``rodcad simulate``).
ALL_EXAMPLES = sorted(p for p in EXAMPLES.glob("*.yaml") if p.stem != "chain")


@pytest.mark.parametrize("example", ALL_EXAMPLES, ids=lambda p: p.stem)
def test_every_example_s_view_draws_in_headless_chromium(example, build_store, tmp_path):
    """The session's build of every example (the one tests/test_build.py and the net tests
    read; a best fit's folder where the example exits 1) opens in headless Chromium and draws
    its structure."""
    code, out, _ = build_store.cli_build(example, "--no-cad", "-q")
    assert code == EXPECTED_EXIT.get(example.stem, 0)
    _check_screenshot(_screenshot(built_folder(out, code), tmp_path))


def test_without_webgl_the_view_draws_on_a_2d_canvas(semicircle, tmp_path):
    _check_screenshot(_screenshot(semicircle, tmp_path, "--disable-webgl"))


def test_the_page_runs_with_webgl_and_fills_its_tables(lampshade, tmp_path):
    dom = _chromium(lampshade / "view.html", tmp_path, "--dump-dom").stdout
    assert 'data-render="webgl"' in dom, dom[:500]
    assert 'class="err"' not in dom
    data = json.loads((lampshade / "design.json").read_text())
    rows = dom.count("<tr")
    assert rows >= len(data["net"]["rods"]) + len(data["net"]["nodes"])
    assert f"{len(data['net']['rods']) + len(data['net']['nodes']) + 12} parts" in dom
