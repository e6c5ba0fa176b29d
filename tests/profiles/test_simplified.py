"""The paper's simplified S1002: two surfaces, the V at S_x, convexity, autodiff.

Independent references: numpy polynomials of the S1002 section table (profiles.md 1.2),
scipy brentq for the intersection, and the full S1002 where the sections coincide.
"""

import jax
import numpy as np
import pytest
from scipy.optimize import brentq

from jaxrail.profiles import S1002, SimplifiedFlange, SimplifiedTread, simplified_s1002

B_TABLE = np.polynomial.Polynomial(
    [0.0, -3.358537058e-02, 1.565681624e-03, -2.810427944e-05, 5.844240864e-08,
     -1.562379023e-08, 5.309217349e-15, -5.957839843e-12, 2.646656573e-13])
FLANK_SLOPE = -2.747477419

WHEEL = simplified_s1002()
TREAD, FLANGE = WHEEL.surfaces
FULL = S1002()
GRID = 2048


NAMES = ("height", "slope", "second", "curvature", "d_curvature")


def _functions(profile):
    """Height, slope, F'', curvature and d curvature/dy, jitted and vmapped as one
    function (one compile per profile); inputs padded to GRID points."""

    def all_at(y):
        return (profile.height(y), profile.slope(y), profile.second_derivative(y),
                profile.curvature(y), jax.grad(profile.curvature)(y))

    compiled = jax.jit(jax.vmap(all_at))

    def pick(index):
        def evaluate(y):
            y = np.atleast_1d(np.asarray(y, dtype=float))
            padded = np.full(GRID, y[0])
            padded[: y.size] = y
            return np.asarray(compiled(padded)[index])[: y.size]

        return evaluate

    return {name: pick(i) for i, name in enumerate(NAMES)}


T = _functions(TREAD)
F = _functions(FLANGE)
_FULL_HEIGHT = jax.jit(jax.vmap(FULL.height))


def FULL_HEIGHT(y):  # noqa: N802 - reads like the other tables
    y = np.asarray(y, dtype=float)
    padded = np.full(GRID, y[0])
    padded[: y.size] = y
    return np.asarray(_FULL_HEIGHT(padded))[: y.size]


def independent_split_mm():
    f26, k = B_TABLE(-26.0), B_TABLE.deriv()(-26.0)
    return brentq(lambda s: f26 + k * (s + 26.0) - (-93.576667419 + 2.747477419 * -s),
                  -38.0, -27.0, xtol=1e-13)


def test_factory_and_domains():
    assert WHEEL.name == "S1002-simplified"
    assert isinstance(TREAD, SimplifiedTread) and isinstance(FLANGE, SimplifiedFlange)
    split = independent_split_mm()
    assert split == pytest.approx(-35.9303, abs=1e-4)
    assert 1e3 * TREAD.domain[0] == pytest.approx(split, abs=1e-9)
    assert TREAD.domain[1] == 0.060
    assert FLANGE.domain == (-0.0695, TREAD.domain[0])
    assert float(WHEEL.nominal_radius) == 0.46
    with pytest.raises(ValueError, match="nominal_radius"):
        simplified_s1002(-1.0)


def test_the_two_surfaces_meet_in_a_v_at_the_split():
    y = np.array([TREAD.domain[0]])
    assert T["height"](y)[0] == pytest.approx(F["height"](y)[0], abs=1e-12)
    assert 1e3 * T["height"](y)[0] == pytest.approx(5.1411, abs=1e-4)
    assert T["slope"](y)[0] == pytest.approx(B_TABLE.deriv()(-26.0), abs=1e-12)
    assert F["slope"](y)[0] == pytest.approx(FLANK_SLOPE, abs=1e-12)
    # the V lies below the real throat (the throat material is removed), deepest at S_x
    s = np.sort(np.append(np.linspace(-38.4, -26.0, 500), independent_split_mm()))
    envelope = np.maximum(T["height"](1e-3 * s), F["height"](1e-3 * s))
    gap_mm = 1e3 * (FULL_HEIGHT(1e-3 * s) - envelope)
    assert gap_mm.min() > -1e-9
    assert gap_mm.max() == pytest.approx(2.672, abs=1e-3)
    assert s[np.argmax(gap_mm)] == pytest.approx(independent_split_mm(), abs=1e-9)


def test_surfaces_equal_s1002_where_they_share_sections():
    tread_s = np.linspace(-0.026, 0.060, 400)
    np.testing.assert_allclose(T["height"](tread_s), FULL_HEIGHT(tread_s), atol=1e-13)
    flange_s = np.linspace(-0.0695, -0.0384267, 400)
    np.testing.assert_allclose(F["height"](flange_s), FULL_HEIGHT(flange_s), atol=1e-13)


def test_continuations_are_straight_lines():
    s = np.linspace(TREAD.domain[0], -0.026, 50)
    expected = 1e-3 * (B_TABLE(-26.0) + B_TABLE.deriv()(-26.0) * (1e3 * s + 26.0))
    np.testing.assert_allclose(T["height"](s), expected, atol=1e-14)
    np.testing.assert_allclose(T["second"](s[:-1]), 0.0, atol=1e-9)
    s = np.linspace(-0.0384267, FLANGE.domain[1], 50)
    expected = 1e-3 * (-93.576667419 - 2.747477419 * 1e3 * s)
    np.testing.assert_allclose(F["height"](s), expected, atol=1e-14)


def test_flange_is_convex_seen_from_the_rail():
    y = np.linspace(*FLANGE.domain, 1500)
    assert F["second"](y).max() < 1e-9  # F'' <= 0: the flange bulges toward the rail
    # convex radii: the arcs F, G, H (20, 12, 20.5 mm); the smallest is the flange tip
    kappa = F["curvature"](y)
    assert 1e3 / -kappa.min() == pytest.approx(12.0, rel=1e-6)


def test_tread_curvature_sign_and_radius_range():
    """The tread keeps S1002's hollow: concave (F'' > 0) for S < +14.08 mm."""
    s = np.linspace(-25.9999, 32.15, 1500)  # at -26 itself the tangent line takes over
    y = 1e-3 * s
    kappa = T["curvature"](y)  # 1/m, positive = concave seen from the rail
    b1, b2 = B_TABLE.deriv(), B_TABLE.deriv(2)
    kappa_table = 1e3 * b2(s) / (1 + b1(s) ** 2) ** 1.5
    np.testing.assert_allclose(kappa, kappa_table, rtol=1e-6, atol=1e-6)
    sign_change = brentq(b2, 10.0, 20.0, xtol=1e-12)
    assert sign_change == pytest.approx(14.0828, abs=1e-3)
    concave = s < sign_change - 0.01
    convex = s > sign_change + 0.01
    assert np.all(kappa[concave] > 0) and np.all(kappa[convex] < 0)
    # concave radius: smallest 51.8 mm at S = -26; 320 mm at the taping line
    assert 1e3 / kappa[concave].max() == pytest.approx(51.77, abs=0.02)
    assert s[np.argmax(kappa)] == pytest.approx(-26.0, abs=0.05)
    zero = np.array([0.0])
    assert 1e3 / T["curvature"](zero)[0] == pytest.approx(319.9, abs=0.1)
    # convex radius >= 196.5 mm, smallest at S = +28.8
    assert 1e3 / -kappa[convex].min() == pytest.approx(196.52, abs=0.02)
    assert s[np.argmin(kappa)] == pytest.approx(28.80, abs=0.05)
    # the straight parts have zero curvature
    np.testing.assert_allclose(T["second"](np.array([0.035, 0.055, -0.030])), 0.0, atol=1e-9)


def _probe_points(profile, joints_mm):
    low, high = profile.domain
    inside = [j for j in joints_mm if low < 1e-3 * j < high]
    return np.concatenate([np.linspace(low, high, 1200), 1e-3 * np.asarray(inside), [low, high]])


@pytest.mark.parametrize("name", ["tread", "flange"])
def test_no_nan_in_derivatives_including_joints_and_ends(name):
    fns = T if name == "tread" else F
    profile = TREAD if name == "tread" else FLANGE
    joints = [32.15796, -26.0] if name == "tread" else [-39.764473993, -49.662510381, -62.764705882]
    y = np.concatenate([_probe_points(profile, joints), [-0.075, -0.070, 0.07]])
    for fn in fns.values():
        assert np.all(np.isfinite(fn(y)))


@pytest.mark.parametrize("name", ["tread", "flange"])
def test_autodiff_against_central_differences(name):
    fns = T if name == "tread" else F
    profile = TREAD if name == "tread" else FLANGE
    joints = 1e-3 * np.array([32.15796, -26.0, -39.764473993, -49.662510381, -62.764705882])
    low, high = profile.domain
    y = np.linspace(low + 1e-4, high - 1e-4, 150)
    y = y[np.min(np.abs(y[:, None] - joints[None, :]), axis=1) > 2e-5]
    step = 1e-6
    fd = (fns["height"](y + step) - fns["height"](y - step)) / (2 * step)
    np.testing.assert_allclose(fns["slope"](y), fd, rtol=1e-6, atol=1e-8)
    fd = (fns["slope"](y + step) - fns["slope"](y - step)) / (2 * step)
    np.testing.assert_allclose(fns["second"](y), fd, rtol=1e-5, atol=1e-4)
    fd = (fns["curvature"](y + step) - fns["curvature"](y - step)) / (2 * step)
    np.testing.assert_allclose(fns["d_curvature"](y), fd, rtol=1e-4, atol=1e-2)
