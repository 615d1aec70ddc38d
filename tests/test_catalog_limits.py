"""Joint limits: the search on synthetic oracles, the exact B-rep against hand
calculations, the shipped catalog's promises, and the disk cache."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
from catalog_testutil import BASE, load

from rodcad.cad.collision import PairScene
from rodcad.catalog.cache import DiskCache
from rodcad.catalog.limits import (
    TOLERANCE_DEG,
    NoFreeAngle,
    all_pair_limits,
    nominal_middle,
    pair_limits,
    pair_limits_detail,
    search_limits,
)
from rodcad.catalog.loader import load_catalog


@pytest.fixture(autouse=True)
def _tmp_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    cache = tmp_path / "cache"
    monkeypatch.setenv("RODCAD_CACHE_DIR", str(cache))
    return cache


# --------------------------------------------------------------------------- search


@dataclass
class P:
    phi: float
    distance: float
    rate: float

    @property
    def contact(self) -> bool:
        return self.distance <= 1e-9


def wedge_oracle(lo: float, hi: float, radius: float = 5.0):
    """A corner at ``radius`` from the axis approaching a face on each side:
    distance = radius * sin(gap angle), contact outside [lo, hi]."""
    calls = []

    def probe(phi: float) -> P:
        calls.append(phi)
        up, down = math.radians(hi - phi), math.radians(phi - lo)
        if up <= 0 or down <= 0:
            return P(phi, 0.0, 0.0)
        if up < down:
            return P(phi, radius * math.sin(up), -radius * math.cos(up))
        return P(phi, radius * math.sin(down), radius * math.cos(down))

    return probe, calls


@pytest.mark.parametrize("lo, hi", [(-3.8183, 3.8183), (-100.0, -30.0), (-47.375, 117.0012), (12.5, 13.0)])
def test_search_finds_both_contacts_within_tolerance(lo: float, hi: float) -> None:
    probe, calls = wedge_oracle(lo, hi)
    found = search_limits(probe, reach=40.0, wall=1.2, starts=(0.0, (lo + hi) / 2))
    assert found[0] == pytest.approx(lo, abs=TOLERANCE_DEG / 2)
    assert found[1] == pytest.approx(hi, abs=TOLERANCE_DEG / 2)
    assert len(calls) < 80


def test_search_reports_none_without_contact_and_raises_without_free_angle() -> None:
    def free(phi: float) -> P:
        return P(phi, 2.0, 0.0)

    assert search_limits(free, reach=40.0, wall=1.2) == (None, None)
    probe, _ = wedge_oracle(-200.0, 150.0)
    assert search_limits(probe, reach=40.0, wall=1.2)[0] is None
    with pytest.raises(NoFreeAngle):
        search_limits(lambda phi: P(phi, 0.0, 0.0), reach=40.0, wall=1.2)


def test_search_does_not_step_over_a_thin_obstacle() -> None:
    # A 0.5 degree wide obstacle at 60 deg that the rate does not announce.
    def probe(phi: float) -> P:
        gap = math.radians(abs(phi - 60.25)) * 30 - math.radians(0.25) * 30
        return P(phi, max(gap, 0.0), 0.0)

    lo, hi = search_limits(probe, reach=30.0, wall=0.1)
    assert hi == pytest.approx(60.0, abs=TOLERANCE_DEG)


# --------------------------------------------------------------------------- B-rep


def hand_square(setback: float, height: float) -> float:
    """Square ends, pin at mid-height: the corners meet at 2 atan(2 s / h)."""
    return math.degrees(2 * math.atan(2 * setback / height))


@pytest.mark.parametrize("setback, height", [(0.2, 12), (0.6, 10)])
def test_square_ends_match_the_hand_calculation(tmp_path: Path, setback: float, height: float) -> None:
    cat = load(tmp_path, BASE.replace("length: 30", f"length: 30\n    section: {{height: {height}}}\n"
                                      f"    ends: {{setback: {setback}}}"))
    lo, hi = pair_limits(cat, "sq-30", "sq-30")
    expected = hand_square(setback, height)
    assert hi == pytest.approx(expected, abs=0.02)
    assert lo == pytest.approx(-expected, abs=0.02)


def test_flush_faces_meet_at_the_sum_of_their_chamfers(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE + """\
    ends: {setback: 0, top_chamfer: 10, bottom_chamfer: 35}
  - name: kink
    length: 20
    ends: {setback: 0, top_chamfer: -15, bottom_chamfer: 20}
""")
    assert pair_limits(cat, "sq-30", "sq-30") == pytest.approx((-70.0, 20.0), abs=0.02)
    assert pair_limits(cat, "kink-20", "kink-20") == pytest.approx((-40.0, -30.0), abs=0.02)
    assert pair_limits(cat, "sq-30", "kink-20") == pytest.approx((-55.0, -5.0), abs=0.02)


def test_proxies_interfere_exactly_when_the_full_solids_do(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE + "    ends: {setback: 0, top_chamfer: -10, bottom_chamfer: 40}\n")
    g = cat["sq-30"].geometry
    lo, hi = pair_limits(cat, "sq-30", "sq-30")
    scene = PairScene(g, g)
    for phi in (lo - 0.05, lo + 0.05, (lo + hi) / 2, hi - 0.05, hi + 0.05, 170.0, -170.0, 0.0):
        assert scene.interferes(phi, full=True) == scene.interferes(phi), phi


def test_shipped_catalog_covers_free_straight_and_concave_stops() -> None:
    cat = load_catalog("pla-pinned")
    lo, hi = pair_limits(cat, "free-30", "free-30")
    assert lo < -90 and hi > 90
    lo, hi = pair_limits(cat, "straight-30", "straight-40")
    assert lo < -90 and hi == pytest.approx(0.0, abs=0.01)
    for family, angle in (("concave20", 20.0), ("concave40", 40.0)):
        lo, hi = pair_limits(cat, f"{family}-20", f"{family}-30")
        assert hi == pytest.approx(-angle, abs=0.01) and lo < -90
    # The curved family bends smoothly where the arcs' tangents line up.
    lo, hi = pair_limits(cat, "arc-30", "arc-30")
    assert lo < nominal_middle(cat["arc-30"].geometry, cat["arc-30"].geometry) < hi


def test_results_are_cached_on_disk(tmp_path: Path, _tmp_cache: Path) -> None:
    cat = load(tmp_path, BASE)
    first = pair_limits_detail(cat, "sq-30", "sq-30")
    assert not first.cached and first.evaluations > 0
    assert list(_tmp_cache.glob("limits/*/*.json"))
    t0 = time.perf_counter()
    again = pair_limits_detail(cat, "sq-30", "sq-30")
    assert time.perf_counter() - t0 < 0.1
    assert again.cached and again.limits_deg == first.limits_deg
    # Any geometry change is a different key.
    other = load(tmp_path, BASE.replace("length: 30", "length: 30\n    ends: {setback: 0.3}"))
    assert not pair_limits_detail(other, "sq-30", "sq-30").cached
    # A disabled cache recomputes.
    assert not pair_limits_detail(cat, "sq-30", "sq-30", cache=DiskCache(enabled=False)).cached


def test_many_pairs_in_worker_processes(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE.replace("length: 30", "length: [20, 30]"))
    serial = all_pair_limits(cat, jobs=1, cache=DiskCache(enabled=False))
    parallel = all_pair_limits(cat, jobs=2)
    assert list(parallel) == [("sq-20", "sq-20"), ("sq-20", "sq-30"), ("sq-30", "sq-20"), ("sq-30", "sq-30")]
    for key, r in parallel.items():
        assert r.limits_deg == pytest.approx(serial[key].limits_deg, abs=1e-9)
        assert r.limits_rad == pytest.approx(tuple(math.radians(x) for x in r.limits_deg))


def test_pairs_that_do_not_mate_are_refused(tmp_path: Path) -> None:
    cat = load(tmp_path, BASE + "  - name: flip\n    length: 30\n    joint: {layout: fork-tongue}\n")
    with pytest.raises(ValueError, match="cannot be joined"):
        pair_limits(cat, "sq-30", "flip-30")
