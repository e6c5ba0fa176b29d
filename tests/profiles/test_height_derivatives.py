"""Closed-form height, slope and second derivative of the named profiles against
automatic differentiation of their heights, over and beyond their domains."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail import enable_float64

enable_float64()

from jaxrail.profiles import Profile, TabulatedProfile, s1002, simplified_s1002, uic60  # noqa: E402

PROFILES = {
    "uic60 1:40": uic60("1:40"),
    "uic60 1:20": uic60("1:20"),
    "uic60 none": uic60("none"),
    "s1002": s1002().surfaces[0],
    "tread": simplified_s1002().surfaces[0],
    "flange": simplified_s1002().surfaces[1],
}


def _autodiff(profile, y):
    """Height, slope and second derivative by reverse mode through ``height`` alone."""
    slope = jax.grad(profile.height)
    return profile.height(y), slope(y), jax.grad(slope)(y)


def _points(profile):
    lo, hi = profile.domain
    width = hi - lo
    return jnp.linspace(lo - 0.05 * width, hi + 0.05 * width, 997)


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_closed_form_equals_autodiff_of_the_height(name):
    profile = PROFILES[name]
    y = _points(profile)
    closed = jax.jit(jax.vmap(profile.height_derivatives))(y)
    reference = jax.jit(jax.vmap(lambda y: _autodiff(profile, y)))(y)
    for got, want, label in zip(closed, reference, ("height", "slope", "second derivative")):
        assert np.all(np.isfinite(got)), label
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-12, err_msg=f"{name} {label}")
    # The slope and second derivative are themselves differentiable, consistently.
    slope_of_height = jax.vmap(jax.grad(lambda y: profile.height_derivatives(y)[0]))(y)
    second_of_slope = jax.vmap(jax.grad(lambda y: profile.height_derivatives(y)[1]))(y)
    np.testing.assert_allclose(slope_of_height, closed[1], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(second_of_slope, closed[2], rtol=1e-10, atol=1e-12)


def test_default_one_pass_derivatives_of_a_generic_profile():
    """A profile without a closed form (a spline) gets all three by forward mode."""
    y = np.linspace(-0.03, 0.03, 25)
    spline = TabulatedProfile.from_points(y, 0.02 * y**2 - 0.5 * y**3)
    assert type(spline).height_derivatives is Profile.height_derivatives
    points = jnp.linspace(-0.035, 0.035, 301)
    closed = jax.jit(jax.vmap(spline.height_derivatives))(points)
    reference = jax.vmap(lambda y: _autodiff(spline, y))(points)
    for got, want in zip(closed, reference):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-14)
