"""TabulatedProfile: accuracy on a circle, C2 at knots, smoothing vs scipy, errors, autodiff.

Independent references: the analytic circle, scipy.interpolate.CubicSpline (natural) and
scipy.interpolate.make_smoothing_spline (same objective), central differences.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import CubicSpline, make_smoothing_spline

from jaxrail.profiles import TabulatedProfile, WheelProfile, tabulated_rail, tabulated_wheel

RADIUS = 0.3
Y_CIRCLE = np.arange(-60, 61) * 0.5e-3  # 0.5 mm spacing over +-30 mm
Z_CIRCLE = np.sqrt(RADIUS**2 - Y_CIRCLE**2) - RADIUS
CIRCLE = TabulatedProfile.from_points(Y_CIRCLE, Z_CIRCLE, name="circle")
GRID = 4096


def _all_at(profile, y):
    return (profile.height(y), profile.slope(y), profile.second_derivative(y),
            profile.curvature(y), jax.grad(profile.curvature)(y))


# The profile is an argument (a pytree), so profiles on any knot grid of the same size share
# one compile.
_COMPILED = jax.jit(jax.vmap(_all_at, in_axes=(None, 0)))


def evaluate(profile, y):
    """(height, slope, second derivative, curvature, d curvature/dy) at points y [m]."""
    y = np.atleast_1d(np.asarray(y, dtype=float))
    padded = np.full(GRID, y[0])
    padded[: y.size] = y
    return tuple(np.asarray(a)[: y.size] for a in _COMPILED(profile, padded))


def test_reproduces_a_circle_arc():
    y = np.linspace(-0.03, 0.03, 3001)
    h, s, _, k, _ = evaluate(CIRCLE, y)
    root = np.sqrt(RADIUS**2 - y**2)
    # whole domain: the natural end condition (f'' = 0) costs accuracy near the ends
    assert np.abs(h - (root - RADIUS)).max() < 1e-7
    # 5 mm or more from the ends: height 1e-12 m, slope 1e-8, curvature 1e-4 1/m (of 3.33)
    inner = np.abs(y) <= 0.025
    assert np.abs(h - (root - RADIUS))[inner].max() < 1e-12
    assert np.abs(s - (-y / root))[inner].max() < 1e-8
    assert np.abs(k - (-1.0 / RADIUS))[inner].max() < 1e-4


def test_interpolates_and_matches_scipy_natural_spline():
    h, *_ = evaluate(CIRCLE, Y_CIRCLE)
    np.testing.assert_allclose(h, Z_CIRCLE, atol=1e-16)
    y = np.linspace(-0.03, 0.03, 2000)
    reference = CubicSpline(Y_CIRCLE, Z_CIRCLE, bc_type="natural")
    h, s, c2, _, _ = evaluate(CIRCLE, y)
    np.testing.assert_allclose(h, reference(y), atol=1e-15)
    np.testing.assert_allclose(s, reference(y, 1), atol=1e-12)
    np.testing.assert_allclose(c2, reference(y, 2), atol=1e-8)


def test_second_derivative_is_continuous_across_knots():
    rng = np.random.default_rng(1)
    y = np.sort(rng.uniform(-0.02, 0.02, 30))
    profile = TabulatedProfile.from_points(y, 1e-3 * np.sin(200 * y) + 1e-4 * rng.normal(size=30))
    eps = 1e-11
    knots = y[1:-1]
    _, s_left, c_left, _, _ = evaluate(profile, knots - eps)
    _, s_right, c_right, _, _ = evaluate(profile, knots + eps)
    scale = np.abs(c_left).max()
    assert np.abs(c_left - c_right).max() < 1e-6 * scale
    # slope: continuous, the difference over 2 eps is just the curvature
    assert np.abs(s_right - s_left - eps * (c_left + c_right)).max() < 1e-9
    # and the third derivative does jump (so the test above can see a break)
    _, _, _, _, dk_left = evaluate(profile, knots - 1e-6)
    _, _, _, _, dk_right = evaluate(profile, knots + 1e-6)
    assert np.abs(dk_left - dk_right).max() > 1.0


@pytest.mark.parametrize("lam", [1e-10, 1e-8, 1e-6])
def test_smoothing_spline_matches_scipy(lam):
    rng = np.random.default_rng(2)
    y = np.sort(rng.uniform(0.0, 0.05, 60))
    z = 1e-3 * np.sin(100 * y) + 2e-5 * rng.normal(size=60)
    profile = TabulatedProfile.from_points(y, z, smoothing=lam)
    reference = make_smoothing_spline(y, z, lam=lam)
    x = np.linspace(y[0], y[-1], 1000)
    h, s, c2, _, _ = evaluate(profile, x)
    np.testing.assert_allclose(h, reference(x), atol=1e-12)
    np.testing.assert_allclose(s, reference(x, 1), atol=1e-9)
    np.testing.assert_allclose(c2, reference(x, 2), atol=1e-5 * np.abs(c2).max())
    assert np.abs(np.asarray(profile.values) - z).max() > 1e-9  # it does smooth


def test_heavy_smoothing_tends_to_the_least_squares_line():
    rng = np.random.default_rng(3)
    y = np.linspace(0.0, 0.04, 50)
    z = 0.01 * y + 1e-4 * rng.normal(size=50)
    profile = TabulatedProfile.from_points(y, z, smoothing=1e3)
    slope, intercept = np.polyfit(y, z, 1)
    h, *_ = evaluate(profile, y)
    np.testing.assert_allclose(h, slope * y + intercept, atol=1e-9)


def test_linear_continuation_outside_the_domain():
    low, high = CIRCLE.domain
    assert (low, high) == (Y_CIRCLE[0], Y_CIRCLE[-1])
    h, s, c2, _, _ = evaluate(CIRCLE, np.array([low, high, low - 0.002, high + 0.003]))
    assert h[2] == pytest.approx(h[0] - 0.002 * s[0], abs=1e-15)
    assert h[3] == pytest.approx(h[1] + 0.003 * s[1], abs=1e-15)
    assert s[2] == pytest.approx(s[0], abs=1e-12) and s[3] == pytest.approx(s[1], abs=1e-12)
    np.testing.assert_allclose(c2, 0.0, atol=1e-9)
    # the slope at the end knots is the spline's own, not halved by a clip
    reference = CubicSpline(Y_CIRCLE, Z_CIRCLE, bc_type="natural")
    assert s[0] == pytest.approx(reference(low, 1), abs=1e-12)


def test_autodiff_against_central_differences_and_no_nan():
    y = np.concatenate([np.linspace(-0.0299, 0.0299, 300), Y_CIRCLE, [-0.03, 0.03, -0.05, 0.05]])
    values = evaluate(CIRCLE, y)
    for v in values:
        assert np.all(np.isfinite(v))
    x = np.linspace(-0.0299, 0.0299, 301) + 0.17e-3  # off the knots
    step = 1e-7
    h_plus, s_plus, _, k_plus, _ = evaluate(CIRCLE, x + step)
    h_minus, s_minus, _, k_minus, _ = evaluate(CIRCLE, x - step)
    _, s, c2, _, dk = evaluate(CIRCLE, x)
    np.testing.assert_allclose(s, (h_plus - h_minus) / (2 * step), atol=1e-8)
    np.testing.assert_allclose(c2, (s_plus - s_minus) / (2 * step), rtol=1e-6, atol=1e-5)
    np.testing.assert_allclose(dk, (k_plus - k_minus) / (2 * step), atol=1e-2)


def test_grad_with_respect_to_spline_values_and_vmap_over_profiles():
    def mean_height(values):
        profile = TabulatedProfile(CIRCLE.knots, values, CIRCLE.second_derivatives, CIRCLE.bounds)
        return jnp.mean(jax.vmap(profile.height)(jnp.linspace(-0.02, 0.02, 41)))

    loss = jax.jit(mean_height)
    grad = np.asarray(jax.jit(jax.grad(mean_height))(CIRCLE.values))
    assert np.all(np.isfinite(grad))
    for i in (20, 60, 80):
        e = np.zeros_like(grad)
        e[i] = 1e-6
        fd = (float(loss(CIRCLE.values + e)) - float(loss(CIRCLE.values - e))) / 2e-6
        assert grad[i] == pytest.approx(fd, abs=1e-9)
    # a batch of profiles on one knot grid stacks and vmaps
    batch = [TabulatedProfile.from_points(Y_CIRCLE, Z_CIRCLE * c) for c in (0.5, 1.0, 2.0)]
    stacked = jax.tree.map(lambda *leaves: jnp.stack(leaves), *batch)
    heights = jax.jit(jax.vmap(lambda p: p.height(0.01)))(stacked)
    height_at = jax.jit(lambda p, y: p.height(y))
    expected = [float(height_at(p, 0.01)) for p in batch]
    np.testing.assert_allclose(np.asarray(heights), expected, rtol=1e-14)


@pytest.mark.parametrize(
    "y, z, message",
    [
        ([0.0, 1.0, np.nan, 3.0], [0, 0, 0, 0], "y has a non-finite"),
        ([0.0, 1.0, 2.0, 3.0], [0, np.inf, 0, 0], "z has a non-finite"),
        ([0.0, 2.0, 1.0, 3.0], [0, 0, 0, 0], "sorted in increasing order"),
        ([0.0, 1.0, 1.0, 3.0], [0, 0, 0, 0], "repeated value"),
        ([0.0, 1.0, 2.0], [0, 0, 0], "at least 4 points"),
        ([0.0, 1.0, 2.0, 3.0], [0, 0, 0], "same length"),
        ([[0.0, 1.0], [2.0, 3.0]], [0, 0, 0, 0], "1-D"),
    ],
)
def test_bad_points_raise(y, z, message):
    with pytest.raises(ValueError, match=message):
        TabulatedProfile.from_points(np.asarray(y, float), np.asarray(z, float))


@pytest.mark.parametrize("smoothing", [-1.0, np.nan, np.inf])
def test_bad_smoothing_raises(smoothing):
    with pytest.raises(ValueError, match="smoothing"):
        TabulatedProfile.from_points(Y_CIRCLE, Z_CIRCLE, smoothing=smoothing)


def test_bad_direct_construction_raises():
    with pytest.raises(ValueError, match="1-D arrays of one length"):
        TabulatedProfile(CIRCLE.knots, CIRCLE.values[:-1], CIRCLE.second_derivatives, (0.0, 1.0))


def test_factories_convert_mm_to_m():
    y_mm = 1e3 * Y_CIRCLE
    z_mm = 1e3 * Z_CIRCLE
    wheel = tabulated_wheel(y_mm, z_mm, nominal_radius=0.45, name="w")
    assert isinstance(wheel, WheelProfile) and wheel.name == "w"
    assert float(wheel.nominal_radius) == 0.45
    surface = wheel.surfaces[0]
    np.testing.assert_allclose(np.asarray(surface.knots), Y_CIRCLE, rtol=1e-15)
    np.testing.assert_allclose(np.asarray(surface.values), Z_CIRCLE, atol=1e-18)
    rail = tabulated_rail(y_mm, z_mm, name="r")
    assert isinstance(rail, TabulatedProfile) and rail.name == "r"
    assert rail.domain == pytest.approx((-0.03, 0.03), abs=1e-15)
    with pytest.raises(ValueError, match="nominal_radius"):
        tabulated_wheel(y_mm, z_mm, nominal_radius=0.0)
    with pytest.raises(ValueError, match="repeated"):
        tabulated_rail([0, 1, 1, 2], [0, 0, 0, 0])
