"""``rodcad calibrate friction``: the coupon's solids and files, the statics that turn a
reading into mu (against independent numerical solutions), the two-load fit, and the CLI's
answers to bad input.

Two coupons are built (about 10 s each): the default pin's through the CLI, bearing-682's
through the API.
"""

from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq, fsolve

from rodcad.catalog.coupon import (
    G,
    Reading,
    angle_for,
    coulomb_coefficient,
    coupon_geometry,
    default_rider,
    fit_friction,
    mu_from_angle,
)
from rodcad.catalog.loader import catalog_from_text, load_catalog
from rodcad.catalog.paths import default_catalog_dir
from rodcad.cli import main


@pytest.fixture(scope="module")
def catalog():
    return load_catalog("pla-parametric")


@pytest.fixture(scope="module")
def cli_coupon(tmp_path_factory):
    """The default coupon, written by the CLI."""
    out = tmp_path_factory.mktemp("coupon") / "steel"
    assert main(["calibrate", "friction", "-o", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def bearing_coupon(catalog, tmp_path_factory):
    """bearing-682's coupon, built and written through the API."""
    from rodcad.cad.coupon import build_coupon, write_coupon

    geom = coupon_geometry(catalog, catalog.pins.option("bearing-682"))
    build = build_coupon(geom)
    write_coupon(build, tmp_path_factory.mktemp("bearing"), profile=catalog.print_settings, printer=catalog.printer)
    return build


# --------------------------------------------------------------------------- the coupon


def _check_files(files: dict[str, Path], volumes: dict[str, float], wheel_closed_form: float) -> None:
    import trimesh

    from rodcad.cad.export import assembly_leaves
    from rodcad.cad.solids import is_valid_solid

    back = dict(assembly_leaves(files["step"]))
    assert sorted(back) == ["stand", "wheel"]
    for name, volume in volumes.items():
        assert is_valid_solid(back[name])
        assert back[name].volume == pytest.approx(volume, rel=1e-6)
        mesh = trimesh.load(str(files[f"{name}.stl"]), force="mesh")
        assert mesh.is_watertight
        assert mesh.volume == pytest.approx(volume, rel=2e-3)
    assert back["wheel"].volume == pytest.approx(wheel_closed_form, rel=1e-6)
    with zipfile.ZipFile(files["3mf"]) as z:
        names = z.namelist()
        assert "Metadata/Slic3r_PE.config" in names
        model = z.read("Metadata/Slic3r_PE_model.config").decode()
        config = z.read("Metadata/Slic3r_PE.config").decode()
    assert 'value="stand"' in model and 'value="wheel"' in model
    assert 'key="fill_density" value="25%"' in model  # the stand only
    assert "; fill_density = 100%" in config  # the wheel: the catalog's profile


def test_cli_coupon_files(cli_coupon, catalog):
    geom = coupon_geometry(catalog, catalog.pins.base)
    files = {"step": cli_coupon / "coupon.step", "stand.stl": cli_coupon / "stand.stl",
             "wheel.stl": cli_coupon / "wheel.stl", "3mf": cli_coupon / "coupon.3mf"}
    from rodcad.cad.export import assembly_leaves

    volumes = {label: float(s.volume) for label, s in assembly_leaves(files["step"])}
    _check_files(files, volumes, geom.wheel_volume())
    assert (cli_coupon / ".rodcad-output").is_file()
    md = (cli_coupon / "calibrate.md").read_text()
    mass = geom.wheel_mass()
    rider, _ = default_rider(geom)
    assert f"M = {mass:.4g} g" in md and f"r = {geom.option.radius:g} mm" in md and f"R = {rider:g} mm" in md
    mu30 = mu_from_angle(30, rider_mass=geom.ball_mass, rider_radius=rider, load_mass=mass + geom.ball_mass,
                         pin_radius=geom.option.radius)
    row = next(line for line in md.splitlines() if line.startswith("| 30 |"))
    assert f"{mu30:.4f}" in row


def test_bearing_coupon(bearing_coupon):
    from build123d import CenterOf

    from rodcad.cad.solids import is_valid_solid

    b = bearing_coupon
    assert is_valid_solid(b.stand) and is_valid_solid(b.wheel)
    _check_files(b.files, {"stand": float(b.stand.volume), "wheel": b.wheel_volume}, b.geometry.wheel_volume())
    c = b.wheel.center(CenterOf.MASS)
    assert abs(c.X) < 1e-6 and abs(c.Y) < 1e-6  # balanced about its hole
    assert b.wheel_mass == pytest.approx(b.wheel_volume * 1.24e-3 + 2 * 0.19)  # with its two bearings


def test_wheel_clears_the_stand(bearing_coupon):
    """The wheel turns on the pin without touching the stand: the nearest approach is the
    hinge's layer gap (at the knuckles), at any angle."""
    from build123d import Axis

    b = bearing_coupon
    for angle in (0.0, 37.0, 90.0):
        assert b.stand.distance_to(b.wheel.rotate(Axis.Z, angle)) == pytest.approx(b.geometry.layer_gap, abs=1e-6)


def test_default_rider_reads(catalog):
    """Pins and sleeves read 10-60 degrees at mid-range friction; bearings, the innermost cup."""
    for o in catalog.pins.options:
        geom = coupon_geometry(catalog, o)
        r, a = default_rider(geom)
        assert r in geom.rider_radii
        if o.kind == "bearing":
            assert r == geom.rider_radii[0] and 0 < a < 10
        else:
            assert 10 <= a <= 60, (o.name, r, a)


def test_pockets_in_pairs(catalog):
    geom = coupon_geometry(catalog, catalog.pins.base)
    centers = np.array([p.center for p in geom.pockets])
    assert np.allclose(centers.sum(axis=0), 0, atol=1e-9)
    for p in geom.pockets:  # every cup has its partner opposite
        assert np.min(np.linalg.norm(centers + np.array(p.center), axis=1)) < 1e-9
    d = np.linalg.norm(centers[:, None] - centers[None], axis=2) + np.eye(len(centers)) * 1e9
    assert d.min() >= geom.cup_diameter + geom.min_wall - 1e-9


# --------------------------------------------------------------------------- the statics


def test_formula_against_the_wheels_statics(catalog):
    """The wheel of point masses (its plastic on the axis, ballast pairs in their cups, the
    rider) turned until the gravity moment about the pin equals mu W r + T, solved with
    brentq: the formula gives mu back."""
    geom = coupon_geometry(catalog, catalog.pins.base)
    m, wheel, r = geom.ball_mass, geom.wheel_mass(), geom.option.radius
    ballast = [p for p in geom.pockets if not p.rider][:6]
    for mu, torque, rider in ((0.3, 0.0, 24.0), (0.15, 0.0, 32.0), (0.25, 0.004, 16.0)):
        masses = np.array([wheel, m] + [m] * len(ballast))
        pts = np.array([(0.0, 0.0), (0.0, -rider)] + [p.center for p in ballast])
        weight = masses.sum() * G / 1000

        def moment(phi: float) -> float:  # gravity about the axis, the wheel turned phi (N mm)
            c, s = math.cos(phi), math.sin(phi)
            x = pts[:, 0] * c - pts[:, 1] * s
            return float(np.sum(masses * G / 1000 * x)) - (mu * weight * r + torque)

        phi = brentq(moment, 1e-9, math.pi / 2)
        beta = math.degrees(phi)
        assert mu_from_angle(beta, rider_mass=m, rider_radius=rider, load_mass=masses.sum(), pin_radius=r,
                             torque=torque) == pytest.approx(mu, rel=1e-9)
        assert angle_for(mu, rider_mass=m, rider_radius=rider, load_mass=masses.sum(), pin_radius=r,
                         torque=torque) == pytest.approx(beta, rel=1e-9)


def test_formula_against_a_pin_in_its_hole():
    """A wheel hung by a hole of radius r_h on a pin of r_p with Coulomb friction mu_c at the
    line contact, solved for its limit (forces and moment, fsolve): the formula's mu is the
    holding moment over W r_p, (r_h / r_p) sin(atan(mu_c)), and coulomb_coefficient inverts it."""
    m, R, M = 0.888, 24.0, 24.9
    rp, rh = 1.5, 1.6
    W = (M + m) * G / 1000
    for mu_c in (0.05, 0.2, 0.4):
        def equations(v):
            beta, psi, n = v
            normal = np.array([math.sin(psi), math.cos(psi)])  # out of the pin at the contact
            tangent = np.array([math.cos(psi), -math.sin(psi)])
            force = n * normal - mu_c * n * tangent  # on the wheel, friction against the rider's pull
            com_x = m * R * math.sin(beta) / (M + m)  # from the hole's centre
            moment = -rh * (-mu_c * n) - W * com_x  # about the hole's centre: r_h n x t = -r_h
            return [force[0], force[1] - W, moment]

        beta, psi, n = fsolve(equations, [0.3, 0.1, W], xtol=1e-13)
        assert np.allclose(equations([beta, psi, n]), 0, atol=1e-12)
        mu = mu_from_angle(math.degrees(beta), rider_mass=m, rider_radius=R, load_mass=M + m, pin_radius=rp)
        assert mu == pytest.approx(rh / rp * math.sin(math.atan(mu_c)), rel=1e-9)
        assert coulomb_coefficient(mu, rp, rh) == pytest.approx(mu_c, rel=1e-9)


def test_two_loads_separate_mu_and_drag(catalog):
    geom = coupon_geometry(catalog, catalog.pins.option("bearing-682"))
    m, r, wheel = geom.ball_mass, geom.option.radius, geom.wheel_mass()
    mu, torque = 0.004, 0.006
    readings = []
    for balls in (0, 12, 24):
        load = wheel + m * (1 + balls)
        a = angle_for(mu, rider_mass=m, rider_radius=8.0, load_mass=load, pin_radius=r, torque=torque)
        readings.append(Reading(a, 8.0, m, load))
    fit = fit_friction(readings, r)
    assert fit.separated and fit.mu == pytest.approx(mu, rel=1e-9) and fit.torque == pytest.approx(torque, rel=1e-9)
    assert fit.friction == pytest.approx((mu, mu), rel=1e-9)
    # noisy readings (half a degree): still near
    rng = np.random.default_rng(3)
    noisy = [Reading(x.angle + rng.normal(0, 0.1), x.rider_radius, m, x.load_mass) for x in readings * 3]
    fit = fit_friction(noisy, r)
    assert fit.mu == pytest.approx(mu, abs=0.003) and fit.torque == pytest.approx(torque, abs=0.002)
    # one load: no drag told apart, mu the readings' mean
    one = [Reading(a, 24.0, m, 30.0) for a in (30.0, 32.0, 34.0)]
    fit = fit_friction(one, 1.5)
    assert not fit.separated and fit.torque == 0.0
    assert fit.mu == pytest.approx(np.mean(fit.per_reading), rel=1e-12)


# --------------------------------------------------------------------------- the CLI


def test_readings_yaml_round_trip(capsys, tmp_path):
    """The YAML printed for readings, pasted into the catalog, loads as the measured option."""
    assert main(["calibrate", "friction", "--angle", "30", "--angle", "33", "--angle", "31"]) == 0
    out = capsys.readouterr().out
    assert "mu over the readings: [" in out and "measured: true" in out
    block = out[out.index("pins:\n"):]
    text = (default_catalog_dir() / "pla-parametric.yaml").read_text() + "\n" + block
    cat = catalog_from_text(text, "pasted.yaml")
    o = cat.pins.option("steel-pin-3")
    assert o.measured and cat.pins.base.measured
    geom = coupon_geometry(cat, o)
    mus = [mu_from_angle(a, rider_mass=geom.ball_mass, rider_radius=24.0, load_mass=geom.wheel_mass() + geom.ball_mass,
                         pin_radius=1.5) for a in (30, 33, 31)]
    assert o.friction == pytest.approx((min(mus), max(mus)), abs=6e-5)
    assert len(cat.pins.options) == len(load_catalog("pla-parametric").pins.options)  # the menu kept whole


def test_readings_per_angle_ballast(capsys):
    assert main(["calibrate", "friction", "--pin", "bearing-682", "--angle", "4", "--angle", "5", "--ballast", "0",
                 "--ballast", "20", "--wheel-mass", "25.3"]) == 0
    out = capsys.readouterr().out
    assert "drag T =" in out and "torque: [" in out and "wheel:" not in out


@pytest.mark.parametrize("argv, words", [
    (["--pin", "bearing682"], ["bearing682:0:0: --pin:", "did you mean 'bearing-682'"]),
    (["--angle", "-5"], ["-5:0:0: --angle:", "at least 0 and below 90"]),
    (["--angle", "90"], ["90:0:0: --angle:"]),
    (["--angle", "20", "--angle", "95", "--ballast", "3"], ["95:0:0: --angle:", "3:0:0: --ballast:", "pairs"]),
    (["--angle", "20", "--wheel-mass", "0"], ["--wheel-mass: must be above 0 g"]),
    (["--angle", "20", "--angle", "21", "--rider", "8", "--rider", "16", "--rider", "24"], ["--rider: give it once"]),
    (["--rider", "16"], ["--rider: is for readings"]),
])
def test_bad_input_exits_2(capsys, argv, words):
    assert main(["calibrate", "friction", *argv]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    for w in words:
        assert w in err


def test_bad_catalog_exits_2(capsys, tmp_path):
    text = (default_catalog_dir() / "pla-parametric.yaml").read_text()
    bad = tmp_path / "bad.yaml"
    bad.write_text(text.replace("tongue_thickness: 5.6", "tongue_thickness: -5.6"))
    assert main(["calibrate", "friction", str(bad), "--angle", "20"]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:" in err and "tongue_thickness" in err and "Traceback" not in err
    line = next(x for x in err.splitlines() if "tongue_thickness" in x)
    assert line.split(":")[1] != "0"  # FILE:LINE:COL with the line


def test_output_folder_not_ours_exits_2(capsys, tmp_path):
    (tmp_path / "mine.txt").write_text("not rodcad's")
    assert main(["calibrate", "friction", "-o", str(tmp_path)]) == 2
    assert "-o:" in capsys.readouterr().err
    assert (tmp_path / "mine.txt").is_file()
