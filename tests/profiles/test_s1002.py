"""S1002 wheel: standard dimensions, joints, smoothing, MBench points, autodiff.

Independent references: a plain numpy re-implementation of the section table
(profiles.md section 1.2), scipy's brentq, the geometric arc table (profiles.md 1.2), and
the CONTACT/Manchester benchmark points in tests/data/MBench_S1002_v3.prw (eve70a/CONTACT,
testbank/profiles/MBench_S1002_v3.prw, Apache-2.0).
"""

from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from jaxrail.profiles import S1002, WheelProfile, s1002
from jaxrail.profiles.s1002 import SECTION_JOINTS_MM

DATA = Path(__file__).parent.parent / "data"
PROFILE = S1002()
GRID = 4096  # every vector evaluation is padded to this length: one compile per function




def _all_at(y):
    return (PROFILE.height(y), PROFILE.slope(y), PROFILE.second_derivative(y),
            PROFILE.curvature(y), jax.grad(PROFILE.curvature)(y))


_COMPILED = jax.jit(jax.vmap(_all_at))  # one compile for all five


def _pick(index):
    def evaluate(y):
        y = np.atleast_1d(np.asarray(y, dtype=float))
        padded = np.full(GRID, y[0])
        padded[: y.size] = y
        return np.asarray(_COMPILED(padded)[index])[: y.size]

    return evaluate


HEIGHT, SLOPE, SECOND, CURVATURE, D_CURVATURE = (_pick(i) for i in range(5))
# scalar versions for root finding
height_at = jax.jit(PROFILE.height)
slope_at = jax.jit(PROFILE.slope)
second_at = jax.jit(PROFILE.second_derivative)

# Tolerances
JOINT_HEIGHT_TOL = 1e-10  # m (1e-7 mm)
JOINT_SLOPE_TOL = 1e-8


def table_mm(s):
    """The section table exactly as printed (no smoothing), numpy, S and F in mm."""
    s = np.asarray(s, dtype=float)
    b = [0.0, -3.358537058e-02, 1.565681624e-03, -2.810427944e-05, 5.844240864e-08,
         -1.562379023e-08, 5.309217349e-15, -5.957839843e-12, 2.646656573e-13]
    c = [-4.320221063e+03, -1.038384026e+03, -1.065501873e+02, -6.051367875,
         -2.054332446e-01, -4.169739389e-03, -4.687195829e-05, -2.252755540e-07]

    def arc(a, r, centre, sign):
        return a + sign * np.sqrt(np.clip(r**2 - (s + centre) ** 2, 0.0, None))

    pieces = [
        (s >= 32.15796, 1.364323640 - 0.066666667 * s),
        ((s < 32.15796) & (s >= -26), np.polynomial.polynomial.polyval(s, b)),
        ((s < -26) & (s >= -35), np.polynomial.polynomial.polyval(s, c)),
        ((s < -35) & (s >= -38.426669071), arc(16.446, 13.0, 26.210665, -1.0)),
        ((s < -38.426669071) & (s >= -39.764473993), -93.576667419 - 2.747477419 * s),
        ((s < -39.764473993) & (s >= -49.662510381), arc(8.834924130, 20.0, 58.558326413, 1.0)),
        ((s < -49.662510381) & (s >= -62.764705882), arc(16.0, 12.0, 55.0, 1.0)),
        (s < -62.764705882, arc(9.519259302, 20.5, 49.5, 1.0)),
    ]
    return np.select([p[0] for p in pieces], [p[1] for p in pieces])


def dense_grid():
    low, high = PROFILE.domain
    joints = 1e-3 * np.asarray(SECTION_JOINTS_MM)
    return np.unique(np.concatenate([np.linspace(low, high, 2501), joints, [low, high]]))


def test_taping_line_and_flange_height():
    assert abs(float(height_at(0.0))) < 1e-12
    assert float(height_at(-0.055)) == pytest.approx(0.028, abs=1e-12)
    assert abs(float(slope_at(-0.055))) < 1e-9
    y = dense_grid()
    h = (HEIGHT(y))
    assert h.max() <= 0.028 + 1e-12
    assert abs(y[np.argmax(h)] + 0.055) < 1e-4
    # refine the maximum with an independent root search of the slope
    top = brentq(lambda s: float(slope_at(s)), -0.058, -0.052, xtol=1e-14)
    assert top == pytest.approx(-0.055, abs=1e-9)


def test_flange_thickness_32_5_mm_at_10_mm_height():
    # on the flank (between tread and flange tip), F = 10 mm
    s10 = brentq(lambda y: float(height_at(y)) - 0.010, -0.0384, -0.035, xtol=1e-14)
    s10_table = brentq(lambda s: float(table_mm(s)) - 10.0, -38.4, -35.0, xtol=1e-12)
    assert 1e3 * s10 == pytest.approx(-37.5, abs=1e-4)
    assert 1e3 * s10 == pytest.approx(s10_table, abs=1e-4)
    assert 1e3 * s10 - (-70.0) == pytest.approx(32.5, abs=1e-4)


def test_flank_is_70_degrees():
    y = np.linspace(-0.0397, -0.0385, 7)  # inside section E
    slope = (SLOPE(y))
    np.testing.assert_allclose(slope, -2.747477419, atol=1e-9)
    assert np.degrees(np.arctan(-slope)) == pytest.approx(70.0, abs=1e-4)
    np.testing.assert_allclose((SECOND(y)), 0.0, atol=1e-9)


@pytest.mark.parametrize(
    "s_centre_mm, radius_mm, sign",
    [(-36.5, 13.0, +1.0), (-45.0, 20.0, -1.0), (-55.0, 12.0, -1.0), (-66.0, 20.5, -1.0)],
)
def test_arc_radii(s_centre_mm, radius_mm, sign):
    # geometric arc table: D concave R13, F R20, G R12, H R20.5 convex (seen from the rail)
    kappa = float(CURVATURE(1e-3 * s_centre_mm)[0])
    assert kappa == pytest.approx(sign * 1e3 / radius_mm, rel=1e-9)


def test_outer_tread_slopes():
    assert float(slope_at(0.0)) == pytest.approx(-0.03358537058, abs=1e-12)
    np.testing.assert_allclose((SLOPE(np.array([0.035, 0.05]))), -0.066666667, atol=1e-12)
    smallest = brentq(lambda y: float(second_at(y)), 0.010, 0.020, xtol=1e-14)
    assert 1e3 * smallest == pytest.approx(14.08, abs=0.01)
    assert abs(float(slope_at(smallest))) == pytest.approx(0.00872, abs=1e-5)


@pytest.mark.parametrize("joint_mm", SECTION_JOINTS_MM)
def test_height_and_slope_continuous_at_joints(joint_mm):
    y = 1e-3 * joint_mm
    eps = 1e-12
    sides = np.array([y - eps, y + eps])
    assert abs(np.diff(HEIGHT(sides))[0]) < JOINT_HEIGHT_TOL
    assert abs(np.diff(SLOPE(sides))[0]) < JOINT_SLOPE_TOL


def test_the_printed_table_has_the_two_rounding_steps():
    # the reason for the smoothing: the raw table jumps at S = -35 and -26
    e = 1e-9
    assert float(table_mm(-35 - e) - table_mm(-35 + e)) == pytest.approx(1.18e-4, abs=0.01e-4)
    assert float(table_mm(-26 - e) - table_mm(-26 + e)) == pytest.approx(-3.65e-5, abs=0.01e-5)


def test_smoothing_changes_only_section_c_and_by_at_most_0_12_um():
    y = dense_grid()
    s = 1e3 * y
    change_mm = 1e3 * (HEIGHT(y)) - table_mm(s)
    in_c = (s <= -26) & (s >= -35)
    # elsewhere only the choice of side at the joints differs (table joints match to 7e-8 mm)
    assert np.abs(change_mm[~in_c]).max() < 1e-7
    assert np.abs(change_mm[in_c]).max() < 1.2e-4
    assert np.abs(change_mm[in_c]).max() > 1.1e-4  # the correction is really there


def read_mbench_points():
    rows = []
    inside = False
    for line in (DATA / "MBench_S1002_v3.prw").read_text().splitlines():
        text = line.split("!")[0].strip()
        if text == "point.begin":
            inside = True
        elif text == "point.end":
            inside = False
        elif inside and text:
            rows.append([float(v) for v in text.split()])
    data = np.asarray(rows)
    return -data[:, 0], data[:, 1]  # the file stores y = -S, z = F


def test_matches_manchester_benchmark_points():
    s, f = read_mbench_points()
    assert s.size == 399
    model = 1e3 * (HEIGHT(1e-3 * s))
    in_c = (s < -26) & (s > -35)
    # outside section C the benchmark equals the table to 1.6e-6 mm (profiles.md 1.2)
    assert np.abs(model - f)[~in_c].max() < 2e-6
    # in C it differs by the smoothing correction only
    correction = model - table_mm(s)
    assert np.abs(model - correction - f)[in_c].max() < 2e-6


def test_autodiff_against_central_differences():
    y = np.linspace(-0.0690, 0.0595, 201)
    y = y[np.min(np.abs(y[:, None] - 1e-3 * np.asarray(SECTION_JOINTS_MM)[None, :]), axis=1) > 2e-5]
    step = 1e-6
    fd_slope = ((HEIGHT(y + step)) - (HEIGHT(y - step))) / (2 * step)
    np.testing.assert_allclose((SLOPE(y)), fd_slope, rtol=1e-6, atol=1e-8)
    fd_second = ((SLOPE(y + step)) - (SLOPE(y - step))) / (2 * step)
    np.testing.assert_allclose((SECOND(y)), fd_second, rtol=1e-5, atol=1e-4)
    fd_dcurv = ((CURVATURE(y + step)) - (CURVATURE(y - step))) / (2 * step)
    np.testing.assert_allclose((D_CURVATURE(y)), fd_dcurv, rtol=1e-4, atol=1e-2)


def test_no_nan_anywhere_including_joints_ends_and_outside():
    y = np.concatenate([dense_grid(), [-0.070, -0.0705, -0.080, 0.065, 0.1]])
    for fn in (HEIGHT, SLOPE, SECOND, CURVATURE, D_CURVATURE):
        assert np.all(np.isfinite(np.asarray(fn(y))))


def test_grad_of_a_scalar_loss_through_height_is_finite_and_correct():
    # reverse mode through vmap (as the contact search uses it)
    @jax.jit
    def loss(shift):
        y = jnp.linspace(-0.0690, 0.0595, 64) + shift
        return jnp.sum(jax.vmap(PROFILE.height)(y) ** 2)

    g = float(jax.jit(jax.grad(loss))(0.0))
    step = 1e-7
    fd = (float(loss(step)) - float(loss(-step))) / (2 * step)
    assert np.isfinite(g)
    assert g == pytest.approx(fd, rel=1e-5)


def test_factory():
    wheel = s1002(0.46)
    assert isinstance(wheel, WheelProfile)
    assert wheel.name == "S1002"
    assert len(wheel.surfaces) == 1 and isinstance(wheel.surfaces[0], S1002)
    radius = jax.jit(jax.vmap(wheel.rolling_radius))(jnp.array([0.0, -0.055]))
    np.testing.assert_allclose(np.asarray(radius), [0.46, 0.488], atol=1e-12)
    assert wheel.nominal_radius.dtype == jnp.float64
    for bad in (0.0, -0.46, float("nan")):
        with pytest.raises(ValueError, match="nominal_radius"):
            s1002(bad)
