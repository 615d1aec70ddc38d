"""The 3D view of a net built with its solids (tests/test_view.py has the rest): the small V net
the session builds with CAD for tests/test_net_build.py and test_netprint.py (this module runs
on their worker, tests/conftest.py SAME_WORKER)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from test_net_build import V_ARGS, V_BUILD
from test_view import _check_mass_colors, _color, _scene, _world_vertices


def test_a_built_net_shows_its_solids_named_as_in_assembly_step(build_store):
    from rodcad.cad.export import read_assembly

    code, out, _ = build_store.cli_build(*V_ARGS, **V_BUILD)
    assert code == 0
    data = json.loads((out / "design.json").read_text())
    scene = _scene(out)
    solids = {label for label, _ in read_assembly(out / "assembly.step")}
    parts = set(scene.graph.nodes_geometry)
    assert solids == {"rod-000", "rod-001", *(f"hub-{k:03d}-{h}" for k in range(3) for h in "ab")}
    assert parts == solids | {"anchor-000", "anchor-002"}
    _check_mass_colors(scene, ["rod-000", "rod-001"], [r["mass"] for r in data["net"]["rods"]])
    a, b = _color(scene, "hub-001-a"), _color(scene, "hub-001-b")
    assert np.ptp(a) < 0.05 and np.ptp(b) < 0.05 and a[0] > b[0] + 0.05  # a hub's halves in two greys
    simulated = np.array(data["as_built"]["simulated"])  # where it hangs as built
    for k in range(3):
        v = np.vstack([_world_vertices(scene, f"hub-{k:03d}-{h}") for h in "ab"])
        assert len(v) > 300  # the solids' meshes: sockets, not spheres
        np.testing.assert_allclose((v.min(axis=0) + v.max(axis=0)) / 2, simulated[k], atol=1.5)
        assert np.ptp(v, axis=0) == pytest.approx([data["hardware"]["diameter"]] * 3, rel=0.05)
