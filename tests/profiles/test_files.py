"""Profile files: CSV round trip and dialects, whole-or-nothing writes, SIMPACK .prw/.prr.

tests/data/MBench_S1002_v3.prw and MBench_UIC60_v3.prr are the Manchester contact
benchmark profiles shipped with CONTACT (github.com/eve70a/CONTACT, testbank/profiles/ and
examples/, Apache-2.0), copied unchanged. Independent references: the S1002 section table
(via S1002, itself checked against the table in test_s1002.py) and the gauge-point position
from profiles.md section 2.1 (gauge 1435 mm, highest point 760.53 mm from the track centre).
"""

import os
from pathlib import Path

import jax
import numpy as np
import pytest

from jaxrail.profiles import (
    S1002,
    TabulatedProfile,
    WheelProfile,
    read_profile,
    sample_profile,
    simplified_s1002,
    write_profile_csv,
)
from jaxrail.profiles.files import read_simpack_points, read_text_points

DATA = Path(__file__).parent.parent / "data"
height_at = jax.jit(lambda profile, y: jax.vmap(profile.height)(y))


def test_csv_round_trip_gives_the_same_points(tmp_path):
    y_mm, z_mm = sample_profile(S1002(), n=301)
    assert y_mm[0] == pytest.approx(-69.5) and y_mm[-1] == pytest.approx(60.0)
    path = tmp_path / "s1002.csv"
    write_profile_csv(path, y_mm, z_mm, header="S1002 sampled\nsecond line")
    y_read, z_read = read_text_points(path)
    np.testing.assert_array_equal(y_read, y_mm)
    np.testing.assert_array_equal(z_read, z_mm)
    wheel = read_profile(path, kind="wheel", nominal_radius=0.45)
    assert isinstance(wheel, WheelProfile) and wheel.name == "s1002.csv"
    surface = wheel.surfaces[0]
    np.testing.assert_array_equal(np.asarray(surface.knots), 1e-3 * y_mm)
    np.testing.assert_allclose(np.asarray(height_at(surface, surface.knots)), 1e-3 * z_mm,
                               atol=1e-17)
    text = path.read_text().splitlines()
    assert text[:3] == ["# S1002 sampled", "# second line", "y_mm,z_mm"]


def test_csv_dialects(tmp_path):
    expected_y = np.array([-2.0, -1.0, 0.5, 1.5, 3.0])
    expected_z = np.array([0.25, 0.0, -0.5, 1.0, 2.0])
    comma = "# comment\ny,z\n" + "".join(f"{a},{b}  # note\n" for a, b in zip(expected_y, expected_z))
    spaces = "\n".join(f"  {a}\t {b}" for a, b in zip(expected_y, expected_z)) + "\n\n"
    semicolon = "y;z\n" + "".join(
        f"{a};{b}\n".replace(".", ",") for a, b in zip(expected_y, expected_z))
    for name, text in [("a.csv", comma), ("b.txt", spaces), ("c.csv", semicolon)]:
        path = tmp_path / name
        path.write_text(text)
        y, z = read_text_points(path)
        np.testing.assert_array_equal(y, expected_y)
        np.testing.assert_array_equal(z, expected_z)


def test_decreasing_points_and_mirror(tmp_path):
    path = tmp_path / "rail.csv"
    path.write_text("3,0\n2,1\n1,4\n0,9\n")
    rail = read_profile(path, kind="rail")
    np.testing.assert_allclose(np.asarray(rail.knots), [0.0, 0.001, 0.002, 0.003])
    np.testing.assert_allclose(np.asarray(rail.values), [0.009, 0.004, 0.001, 0.0])
    mirrored = read_profile(path, kind="rail", mirror_y=True)
    np.testing.assert_allclose(np.asarray(mirrored.knots), [-0.003, -0.002, -0.001, 0.0])
    np.testing.assert_allclose(np.asarray(mirrored.values), [0.0, 0.001, 0.004, 0.009])


@pytest.mark.parametrize(
    "text, message",
    [
        ("1,2,3\n2,3,4\n3,4,5\n4,5,6\n", "expected 2 columns"),
        ("y,z\n1,2\nfoo,bar\n3,4\n4,5\n", "cannot read 'foo'"),
        ("# only comments\n", "no profile points"),
        ("0,0\n1,nan\n2,0\n3,0\n", "non-finite"),
        ("0,0\n2,0\n1,0\n3,0\n", "sorted"),
    ],
)
def test_bad_csv_raises(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        read_profile(path, kind="rail")


def test_kind_is_required_for_text_and_checked(tmp_path):
    path = tmp_path / "p.csv"
    write_profile_csv(path, [0, 1, 2, 3], [0, 1, 4, 9])
    with pytest.raises(ValueError, match="kind must be given"):
        read_profile(path)
    with pytest.raises(ValueError, match="kind must be 'wheel' or 'rail'"):
        read_profile(path, kind="axle")
    with pytest.raises(ValueError, match="kind='rail' but"):
        read_profile(DATA / "MBench_S1002_v3.prw", kind="rail")


def test_mirrored_wheel_is_refused(tmp_path):
    y_mm, z_mm = sample_profile(S1002(), n=200)
    path = tmp_path / "mirrored.csv"
    write_profile_csv(path, -y_mm[::-1], z_mm[::-1])
    with pytest.raises(ValueError, match="mirror_y=True"):
        read_profile(path, kind="wheel")
    wheel = read_profile(path, kind="wheel", mirror_y=True)
    np.testing.assert_allclose(1e3 * np.asarray(wheel.surfaces[0].knots), y_mm, atol=1e-12)


def test_write_is_whole_or_nothing(tmp_path, monkeypatch):
    path = tmp_path / "keep.csv"
    write_profile_csv(path, [0, 1, 2, 3], [0, 1, 4, 9])
    before = path.read_bytes()
    # bad data: refused before anything is written
    with pytest.raises(ValueError, match="non-finite"):
        write_profile_csv(path, [0, 1, 2, 3], [0, np.nan, 4, 9])
    # failure at the last step: the old file stays, no temporary file is left
    def failing_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError, match="disk full"):
        write_profile_csv(path, [0, 1, 2, 3, 4], [0, 1, 4, 9, 16])
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.csv"]


def test_sample_profile_of_a_two_surface_wheel():
    wheel = simplified_s1002()
    y_mm, z_mm = sample_profile(wheel, n=1001)
    assert y_mm[0] == pytest.approx(-69.5) and y_mm[-1] == pytest.approx(60.0)
    assert np.all(np.diff(y_mm) > 0)
    full_y, full_z = sample_profile(S1002(), n=1001)
    np.testing.assert_array_equal(y_mm, full_y)
    # equal to S1002 outside the throat, below it (the V) inside
    outside = (y_mm > -26.0) | (y_mm < -38.43)
    np.testing.assert_allclose(z_mm[outside], full_z[outside], atol=1e-10)
    assert np.all(z_mm[~outside] <= full_z[~outside] + 1e-9)
    tread_y, _ = sample_profile(wheel, n=11, surface=0)
    assert tread_y[0] == pytest.approx(1e3 * wheel.surfaces[0].domain[0])
    with pytest.raises(ValueError, match="surface"):
        sample_profile(wheel, surface=2)
    with pytest.raises(ValueError, match="n must be"):
        sample_profile(wheel, n=1)


def test_reads_the_mbench_s1002_prw():
    y_m, z_m, fields = read_simpack_points(DATA / "MBench_S1002_v3.prw")
    assert fields["header.type"] == 1.0
    assert y_m.size == 399  # the commented first point (flange back) is skipped
    # after the file's mirror.y and inversion: S in m, flange at negative y
    assert y_m[0] == pytest.approx(0.060) and y_m[-1] == pytest.approx(-0.069612628)
    wheel = read_profile(DATA / "MBench_S1002_v3.prw", nominal_radius=0.46)
    assert isinstance(wheel, WheelProfile) and wheel.name == "MBench_S1002_v3.prw"
    surface = wheel.surfaces[0]
    assert surface.domain == pytest.approx((-0.069612628, 0.060))
    s_mm = 1e3 * np.asarray(surface.knots)
    z_mm = 1e3 * np.asarray(height_at(surface, surface.knots))
    reference = 1e3 * np.asarray(height_at(S1002(), np.clip(surface.knots, -0.0695, 0.06)))
    away_from_c = ((s_mm > -25.9) | (s_mm < -35.1)) & (s_mm > -69.5)
    assert np.abs(z_mm - reference)[away_from_c].max() < 2e-6  # mm
    # the flange: 28 mm high at S = -55
    fine = np.linspace(-0.060, -0.050, 2001)
    h = 1e3 * np.asarray(height_at(surface, fine))
    assert h.max() == pytest.approx(28.0, abs=1e-3)
    assert 1e3 * fine[np.argmax(h)] == pytest.approx(-55.0, abs=0.05)


def test_reads_the_mbench_uic60_prr_without_double_cant():
    rail = read_profile(DATA / "MBench_UIC60_v3.prr")
    assert isinstance(rail, TabulatedProfile) and rail.name == "MBench_UIC60_v3.prr"
    low, high = rail.domain
    assert 1e3 * low == pytest.approx(-43.704898) and 1e3 * high == pytest.approx(30.595912)
    y = np.linspace(low, high, 4001)
    h = 1e3 * np.asarray(height_at(rail, y))
    # origin at the highest point, height up (the file's z points down)
    assert h.max() == pytest.approx(0.0, abs=1e-4)
    assert abs(1e3 * y[np.argmax(h)]) < 0.1
    assert h[0] < -38 and h[-1] < -36
    # gauge point 14 mm below the top on the gauge side (negative y): for gauge 1435 mm and
    # the top 760.53 mm from the track centre it is at 717.5 - 760.53 = -43.03 mm
    gauge_side = y < -0.040
    crossing = y[gauge_side][np.argmin(np.abs(h[gauge_side] + 14.0))]
    assert 1e3 * crossing == pytest.approx(-43.03, abs=0.02)


def test_simpack_processing_steps(tmp_path):
    """shift, rotate, bounds, mirror, inversion and units on a tiny synthetic file."""
    header = """header.begin
  type = 0   ! rail
header.end
spline.begin
  shift.y = 1.0
  shift.z = -0.5
  bound.y.min = 0.0
  bound.y.max = 10.0
  mirror.y = 1
  mirror.z = 1
  inversion = 1
  units.len.f = 100.0   ! user units per metre
  point.begin
"""
    points = "-2 0\n0 0\n1 1\n2 4\n3 9 0.5\n4 16\n"
    path = tmp_path / "t.prr"
    path.write_text(header + points + "  point.end\nspline.end\n")
    y, z, fields = read_simpack_points(path)
    # shift: y+1, z-0.5 -> drop y<0 (the -2 point becomes -1) -> mirror both -> invert
    np.testing.assert_allclose(y, np.array([-5, -4, -3, -2, -1]) / 100)
    np.testing.assert_allclose(z, np.array([-15.5, -8.5, -3.5, -0.5, 0.5]) / 100)
    assert fields["spline.units.len.f"] == 100.0
    rail = read_profile(path)
    np.testing.assert_allclose(np.asarray(rail.values), -z)  # rail height = -z
    rotated = tmp_path / "r.prw"
    rotated.write_text("header.begin\n type = 1\nheader.end\nspline.begin\n rotate = 90\n"
                       " units.ang.f = 57.29577951308232\n units.len.f = 1000\n point.begin\n"
                       "1 0\n0 2\n point.end\nspline.end\n")
    y, z, _ = read_simpack_points(rotated)
    np.testing.assert_allclose(y, [0.0, -0.002], atol=1e-15)
    np.testing.assert_allclose(z, [0.001, 0.0], atol=1e-15)


def test_bad_simpack_files(tmp_path):
    path = tmp_path / "bad.prw"
    path.write_text("header.begin\n type = 1\nheader.end\nspline.begin\n point.begin\n"
                    "1 2 3 4\n point.end\nspline.end\n")
    with pytest.raises(ValueError, match="expected y z"):
        read_profile(path)
    path.write_text("foo.begin\nfoo.end\n")
    with pytest.raises(ValueError, match="unknown block 'foo'"):
        read_profile(path)
    path.write_text("header.begin\nheader.end\nspline.begin\n point.begin\n point.end\nspline.end\n")
    with pytest.raises(ValueError, match="no points"):
        read_profile(path)
    rail = "header.begin\n type = 0\nheader.end\nspline.begin\n{} point.begin\n{}point.end\nspline.end\n"
    points_mm = "".join(f"{y} {-(y / 10) ** 2}\n" for y in range(-35, 36, 5))
    path = tmp_path / "bad.prr"
    path.write_text(rail.format("", points_mm))  # millimetres without units.len.f
    with pytest.raises(ValueError, match=r"the profile is 70 m wide, not a rail profile "
                       r"\(10-500 mm\): check units.len.f \(missing, so metres; 1000"):
        read_profile(path)
    path.write_text(rail.format(" units.len.f = 1000\n mirror.y = abc\n", points_mm))
    with pytest.raises(ValueError, match="spline.mirror.y must be a number, got 'abc'"):
        read_profile(path)
    path.write_text(rail.format(" units.len.f = 1000\n mirror.y = 2\n", points_mm))
    with pytest.raises(ValueError, match="spline.mirror.y must be 0 or 1, got 2"):
        read_profile(path)
    path.write_text(rail.format(" units.len.f = 1000\n", points_mm))
    assert float(np.ptp(read_simpack_points(path)[0])) == pytest.approx(0.07)
