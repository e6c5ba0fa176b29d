"""FASTSIM patch (jaxrail.wear.fastsim): checked against Kalker's linear theory (small
creepage and spin, closed forms with kalker_coefficients), Coulomb's full-sliding limit
|F| = mu N opposite the creepage, the normal force (sum of the pressure), the parabolic
traction bound recomputed from the element centres, the slip/traction directions, the
empty patch, and jit / vmap / grad against a Python loop and central differences."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.kalker import kalker_coefficients
from jaxrail.wear.fastsim import ELEMENTS, STRIPS, PatchGrid, fastsim_patch

G, NU = 8.2e10, 0.28  # steel, the module's defaults
N, MU, A, B = 8.0e4, 0.4, 6.0e-3, 5.0e-3

LINEAR_RTOL = 5e-3  # discretisation (21 strips x 24 elements) against Kalker's linear theory
SATURATION_RTOL = 1e-2  # |F| against mu N at full sliding
ANGLE_TOL = 1e-3  # [rad] force direction against minus the creepage direction
NORMAL_RTOL = 1e-12  # sum of the pressure against N (scaled to be exact)
BOUND_RTOL = 1e-9  # element traction against mu times the scaled parabolic bound
ANTIPARALLEL_COS = -0.99  # slip against traction in the slip elements
FD_RTOL = 1e-5  # derivatives against central differences


@jax.jit
def _patch(n, a, b, xi, eta, phi, mu):
    return fastsim_patch(n, a, b, xi, eta, phi, mu, G, NU)


def _forces(n, a, b, xi, eta, phi, mu):
    fx, fy = _patch(n, a, b, xi, eta, phi, mu).forces()
    return float(fx), float(fy)


@jax.jit
def _force_vector(p):
    """p = (N, a, b, xi, eta, phi, mu) -> (fx, fy)."""
    return jnp.stack(fastsim_patch(*p, G, NU).forces())


def _parabolic_bound(grid, n, a, b, mu):
    """mu p_F at the element centres, p_F = 2N/(pi a b)(1 - x^2/a^2 - y^2/b^2) scaled, as
    the module docstring says, so that sum p_F dA = N over the elements."""
    x, y, area = (np.asarray(v) for v in (grid.x, grid.y, grid.area))
    shape = 2.0 * n / (math.pi * a * b) * (1.0 - x**2 / a**2 - y**2 / b**2)
    return mu * shape * n / np.sum(shape * area)


ASPECTS = [(A, B), (3.0e-3, 6.0e-3), (8.0e-3, 4.0e-3)]  # a/b = 1.2, 0.5, 2


@pytest.mark.parametrize("a,b", ASPECTS)
def test_linear_theory_limits(a, b):
    c11, c22, c23 = (float(c) for c in kalker_coefficients(a / b, NU))
    c = math.sqrt(a * b)
    small, phi = 1e-6, 1e-4  # [-], [1/m]: all elements stick
    grid = _patch(N, a, b, small, 0.0, 0.0, MU)
    assert bool(np.all(grid.stick))
    fx, fy = (float(f) for f in grid.forces())
    assert fx == pytest.approx(-G * a * b * c11 * small, rel=LINEAR_RTOL)
    assert abs(fy) < 1e-9 * abs(fx)

    grid = _patch(N, a, b, 0.0, small, 0.0, MU)
    assert bool(np.all(grid.stick))
    fx, fy = (float(f) for f in grid.forces())
    assert fy == pytest.approx(-G * a * b * c22 * small, rel=LINEAR_RTOL)
    assert abs(fx) < 1e-9 * abs(fy)

    grid = _patch(N, a, b, 0.0, 0.0, phi, MU)
    assert bool(np.all(grid.stick))
    fx, fy = (float(f) for f in grid.forces())
    assert fy == pytest.approx(-G * c**3 * c23 * phi, rel=LINEAR_RTOL)
    assert abs(fx) < 1e-9 * abs(fy)  # zero by symmetry in y


@pytest.mark.parametrize("xi,eta", [(0.05, 0.0), (0.0, -0.05), (0.03, -0.04), (-0.02, 0.03)])
def test_full_sliding_gives_mu_n_opposite_the_creepage(xi, eta):
    grid = _patch(N, A, B, xi, eta, 0.0, MU)
    assert not bool(np.any(grid.stick))
    fx, fy = (float(f) for f in grid.forces())
    assert math.hypot(fx, fy) == pytest.approx(MU * N, rel=SATURATION_RTOL)
    # angle between F and -creepage, wrapped to (-pi, pi]
    d = math.atan2(fy, fx) - math.atan2(-eta, -xi)
    assert abs(math.remainder(d, 2.0 * math.pi)) < ANGLE_TOL


@pytest.mark.parametrize("a,b", ASPECTS)
def test_hertz_pressure_sums_to_normal_force(a, b):
    grid = _patch(N, a, b, 5e-4, 2e-4, 0.3, MU)
    total = float(jnp.sum(grid.pressure * grid.area))
    assert total == pytest.approx(N, rel=NORMAL_RTOL)
    # and it is the Hertz shape: pressure / sqrt(1 - x^2/a^2 - y^2/b^2) is one constant,
    # within the discretisation of 3N/(2 pi a b)
    x, y = np.asarray(grid.x), np.asarray(grid.y)
    ratio = np.asarray(grid.pressure) / np.sqrt(1.0 - x**2 / a**2 - y**2 / b**2)
    np.testing.assert_allclose(ratio, ratio.flat[0], rtol=1e-12)
    assert ratio.flat[0] == pytest.approx(3.0 * N / (2.0 * math.pi * a * b), rel=LINEAR_RTOL)
    # the grid covers the ellipse's area pi a b within the discretisation
    area = np.asarray(grid.area)
    assert float(np.sum(area)) == pytest.approx(math.pi * a * b, rel=LINEAR_RTOL)


def test_area_has_the_documented_shape():
    grid = _patch(N, A, B, 5e-4, 0.0, 0.0, MU)
    assert np.asarray(grid.area).shape == (STRIPS, ELEMENTS)
    assert float(jnp.sum(grid.area)) == pytest.approx(math.pi * A * B, rel=LINEAR_RTOL)


def test_parabolic_bound_is_the_simplified_theory_within_the_discretisation():
    # the module scales the parabola so that sum p_F dA = N; the scale differs from
    # 2N/(pi a b) by the discretisation only
    grid = _patch(N, A, B, 0.05, 0.0, 0.0, MU)
    x, y, area = (np.asarray(v) for v in (grid.x, grid.y, grid.area))
    shape = 1.0 - x**2 / A**2 - y**2 / B**2
    scale = N / np.sum(shape * area)
    assert scale == pytest.approx(2.0 * N / (math.pi * A * B), rel=LINEAR_RTOL)


@pytest.mark.parametrize("xi,eta", [(0.05, 0.0), (5e-4, 0.0), (3e-4, -4e-4)])
def test_traction_never_exceeds_mu_times_the_parabolic_bound(xi, eta):
    # The bound is recomputed from the element centres, scaled exactly as the module
    # docstring says (sum p_F dA = N): exact comparison, only rounding is allowed.
    grid = _patch(N, A, B, xi, eta, 0.0, MU)
    bound = _parabolic_bound(grid, N, A, B, MU)
    size = np.hypot(grid.traction_x, grid.traction_y)
    assert np.all(size <= bound * (1.0 + BOUND_RTOL))


def test_full_sliding_traction_is_mu_times_the_bound_in_every_element():
    grid = _patch(N, A, B, 0.05, 0.0, 0.0, MU)
    bound = _parabolic_bound(grid, N, A, B, MU)
    size = np.hypot(grid.traction_x, grid.traction_y)
    np.testing.assert_allclose(size, bound, rtol=1e-12)


@pytest.mark.parametrize("xi,eta,phi", [
    (5e-4, 0.0, 0.0), (3e-4, -4e-4, 0.0), (0.05, 0.0, 0.0), (-0.03, 0.04, 0.0),
    (2e-4, 1e-4, 0.5), (0.0, 0.0, 5.0)])
def test_slip_zero_in_stick_antiparallel_in_slip(xi, eta, phi):
    grid = _patch(N, A, B, xi, eta, phi, MU)
    stick = np.asarray(grid.stick)
    sx, sy = np.asarray(grid.slip_x), np.asarray(grid.slip_y)
    tx, ty = np.asarray(grid.traction_x), np.asarray(grid.traction_y)
    assert np.all(sx[stick] == 0.0) and np.all(sy[stick] == 0.0)
    np.testing.assert_allclose(np.asarray(grid.sliding), np.hypot(sx, sy), rtol=1e-15)
    slipping = ~stick
    assert slipping.any()
    tau = np.hypot(tx, ty)
    s = np.hypot(sx, sy)
    sizeable = slipping & (tau > 1e-6 * tau.max()) & (s > 0.0)
    assert sizeable.sum() >= 0.5 * slipping.sum()
    cos = (sx * tx + sy * ty)[sizeable] / (s * tau)[sizeable]
    assert np.all(cos < ANTIPARALLEL_COS)





@pytest.mark.parametrize("n,a,b", [(0.0, A, B), (N, 0.0, B), (N, A, 0.0), (-5.0, A, B)])
def test_empty_patch_is_zero_with_finite_gradients(n, a, b):
    grid = _patch(n, a, b, 1e-3, -2e-3, 0.4, MU)
    for name in ("x", "y", "area", "pressure", "traction_x", "traction_y", "slip_x",
                 "slip_y", "sliding", "strip_y"):
        value = np.asarray(getattr(grid, name))
        assert np.all(value == 0.0), name
    assert bool(np.all(grid.stick))
    assert np.asarray(grid.x).shape == (STRIPS, ELEMENTS)

    def total(*p):
        fx, fy = fastsim_patch(*p).forces()
        return fx + fy

    args = (n, a, b, 1e-3, -2e-3, 0.4, MU, G, NU)
    grads = jax.jit(jax.grad(total, argnums=tuple(range(9))))(*args)
    assert all(np.isfinite(float(g)) for g in grads)


def test_jit_matches_eager():
    eager = fastsim_patch(N, A, B, 5e-4, -2e-4, 0.3, MU, G, NU)
    jitted = _patch(N, A, B, 5e-4, -2e-4, 0.3, MU)
    for name in ("traction_x", "traction_y", "slip_x", "sliding", "pressure"):
        np.testing.assert_allclose(np.asarray(getattr(jitted, name)),
                                   np.asarray(getattr(eager, name)), rtol=1e-12, atol=1e-6)


def test_vmap_matches_python_loop():
    batch = np.array([[N, A, B, 5e-4, 0.0, 0.0, MU],
                      [6e4, 3e-3, 6e-3, -1e-3, 2e-3, 0.7, 0.3],
                      [1e5, 8e-3, 4e-3, 0.05, -0.01, -0.2, 0.5]])
    grids = jax.jit(jax.vmap(lambda p: fastsim_patch(*p, G, NU)))(batch)
    assert isinstance(grids, PatchGrid)
    assert np.asarray(grids.traction_x).shape == (3, STRIPS, ELEMENTS)
    fx, fy = grids.forces()
    for i, p in enumerate(batch):
        one = _patch(*p)
        ref = [float(f) for f in one.forces()]
        assert float(fx[i]) == pytest.approx(ref[0], rel=1e-12)
        assert float(fy[i]) == pytest.approx(ref[1], rel=1e-12)
        np.testing.assert_array_equal(np.asarray(grids.stick[i]), np.asarray(one.stick))


def test_gradients_at_partial_slip_match_central_differences():
    p = np.array([N, A, B, 5e-4, 2e-4, 0.0, MU])
    grid = _patch(*p)
    stick = np.asarray(grid.stick)
    assert stick.any() and not stick.all()  # partial slip
    jac = np.asarray(jax.jit(jax.jacfwd(_force_vector))(p))  # (2, 7)
    # (output, input, step): steps small enough that no element changes between stick
    # and slip, large enough that rounding (~1e-12 of the force) stays below 1e-7
    for out, k, h in [(0, 3, 1e-9), (1, 4, 1e-9), (0, 0, 1e-2)]:
        up, down = p.copy(), p.copy()
        up[k] += h
        down[k] -= h
        fd = (float(_force_vector(up)[out]) - float(_force_vector(down)[out])) / (2 * h)
        assert jac[out, k] == pytest.approx(fd, rel=FD_RTOL), (out, k)
    # and a sign check: more creepage, more (negative) force
    assert jac[0, 3] < 0.0 and jac[1, 4] < 0.0 and jac[0, 0] < 0.0


@pytest.mark.parametrize("p", [
    [N, A, B, 0.0, 0.0, 0.0, MU],      # zero creepage
    [0.0, A, B, 5e-4, 2e-4, 0.1, MU],  # zero normal force
    [0.0, A, B, 0.0, 0.0, 0.0, MU],    # both
])
def test_gradients_finite_at_zero_creepage_and_zero_load(p):
    jac = np.asarray(jax.jit(jax.jacrev(_force_vector))(np.array(p, dtype=float)))
    assert np.all(np.isfinite(jac))
    if p[0] > 0.0:
        # at zero creepage the patch sticks: the slope is Kalker's linear theory
        c11, c22, _ = (float(c) for c in kalker_coefficients(A / B, NU))
        assert jac[0, 3] == pytest.approx(-G * A * B * c11, rel=LINEAR_RTOL)
    else:
        assert np.all(jac == 0.0)


def test_lateral_slope_just_off_zero_creepage_is_kalkers():
    # one-sided: a tiny pure lateral creepage gives Kalker's c22 slope
    c22 = float(kalker_coefficients(A / B, NU)[1])
    jac = np.asarray(jax.jit(jax.jacrev(_force_vector))(
        np.array([N, A, B, 0.0, 1e-9, 0.0, MU])))
    assert jac[1, 4] == pytest.approx(-G * A * B * c22, rel=LINEAR_RTOL)
