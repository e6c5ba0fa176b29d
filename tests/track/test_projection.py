"""Projection onto the track (paper eqs. 3-5): round trips, exact circles, gradients."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail import track as T

R, LT, LA, LS = 300.0, 80.0, 200.0, 50.0  # radius, transition, arc, straight [m]
CANT = 0.150  # m
BASE = 1.5  # m
TOL = 1e-9  # m, round trips
N = 256  # fixed batch size: one compile per track structure


def make_curve(direction="left", radius=R):
    return T.Track.from_segments(T.curve_layout(radius, direction, CANT, LS, LT, LA, LS))


LEFT = make_curve("left")
RIGHT = make_curve("right")
TOTAL = 2 * LS + 2 * LT + LA
ARC_R = 180.0
ARC_L = 0.95 * 2 * np.pi * ARC_R
ARC_CANT = 0.12
ARC = T.Track.from_segments([T.Arc(ARC_L, ARC_R, "left", ARC_CANT)])  # starts at origin, heading 0


def _round_trip(track, s, lateral, vertical):
    p = T.from_track_coordinates(track, s, lateral, vertical)
    s2, lat2, vert2 = T.to_track_coordinates(track, p)
    return p, s2, lat2, vert2, T.from_track_coordinates(track, s2, lat2, vert2)


def _project_all(track, p, s_guess):
    """Track coordinates of p, projection from s_guess, and the frame data at s."""
    s, lat, vert = T.to_track_coordinates(track, p)
    s_from_guess = T.project(track, p, s_guess)
    tangent = T.track_frame(track, s)[:, 0]
    kappa, centre = T.curvature(track, s), T.centreline_position(track, s)
    return s, lat, vert, s_from_guess, tangent, kappa, centre


_round_trip_v = jax.jit(jax.vmap(_round_trip, (None, 0, 0, 0)))
_project_v = jax.jit(jax.vmap(_project_all, (None, 0, 0)))


def pad(x, n=N):
    x = np.asarray(x, dtype=np.float64)
    return np.concatenate([x, np.zeros((n - len(x),) + x.shape[1:])])


def round_trip(track, s, lateral, vertical):
    k = len(s)
    out = _round_trip_v(track, pad(s), pad(lateral), pad(vertical))
    return [np.asarray(o[:k]) for o in out]


def project_all(track, points, s_guess=None):
    """(s, lateral, vertical, s from s_guess, t, kappa, centreline) per point."""
    k = len(points)
    s_guess = np.zeros(k) if s_guess is None else s_guess
    return [np.asarray(o[:k]) for o in _project_v(track, pad(points), pad(s_guess))]


def sample_points(total, k=200, seed=0):
    rng = np.random.default_rng(seed)
    joints = [LS, LS + LT, LS + LT + LA, LS + 2 * LT + LA]
    s = np.concatenate([np.linspace(0.0, total, k - 24), joints])
    s = np.concatenate([s, s[-4:] + 1e-6, s[-4:] - 1e-6, rng.uniform(-10.0, total + 10.0, 12)])
    lateral = rng.uniform(-2.0, 2.0, s.size)
    vertical = rng.uniform(-0.5, 1.0, s.size)
    return s, lateral, vertical


@pytest.mark.parametrize("track", [LEFT, RIGHT], ids=["left", "right"])
def test_round_trip_over_curve(track):
    s, lat, vert = sample_points(TOTAL)
    p, s2, lat2, vert2, p2 = round_trip(track, s, lat, vert)
    np.testing.assert_allclose(s2, s, rtol=0, atol=TOL)
    np.testing.assert_allclose(lat2, lat, rtol=0, atol=TOL)
    np.testing.assert_allclose(vert2, vert, rtol=0, atol=TOL)
    assert np.max(np.linalg.norm(p2 - p, axis=1)) < TOL


def test_exact_straight():
    rng = np.random.default_rng(1)
    x, y, z = rng.uniform(-30, LS - 5, 50), rng.uniform(-5, 5, 50), rng.uniform(-1, 1, 50)
    pts = np.stack([x, y, z], 1)
    # The entry straight runs along X from the origin (extended before it): s = X,
    # lateral = Y, vertical = Z.
    s, lat, vert = project_all(LEFT, pts)[:3]
    np.testing.assert_allclose(s, pts[:, 0], atol=TOL)
    np.testing.assert_allclose(lat, pts[:, 1], atol=TOL)
    np.testing.assert_allclose(vert, pts[:, 2], atol=TOL)


def test_exact_canted_circle():
    # Points around the lone arc (centre (0, ARC_R)), at polar angle a and horizontal
    # distance rho from the centre: s = ARC_R a; the horizontal offset toward the centre
    # h = ARC_R - rho and the height z give the canted coordinates.
    rng = np.random.default_rng(2)
    a = rng.uniform(0.0, ARC_L / ARC_R, 100)
    rho = ARC_R - rng.uniform(-5.0, 5.0, 100)
    z = rng.uniform(-0.5, 1.0, 100)
    pts = np.stack([rho * np.sin(a), ARC_R - rho * np.cos(a), z], 1)
    s, lat, vert = project_all(ARC, pts)[:3]
    phi = np.arcsin(ARC_CANT / BASE)
    h = ARC_R - rho
    np.testing.assert_allclose(s, ARC_R * a, rtol=0, atol=TOL)
    np.testing.assert_allclose(lat, h * np.cos(phi) - z * np.sin(phi), rtol=0, atol=TOL)
    np.testing.assert_allclose(vert, h * np.sin(phi) + z * np.cos(phi), rtol=0, atol=TOL)


def test_s_guess_and_beyond_ends():
    s_true = np.array([LS + 10.0, LS + LT + 120.0, -15.0, TOTAL + 25.0])
    pts = round_trip(LEFT, s_true, np.full(4, 1.2), np.full(4, 0.3))[0]
    got = project_all(LEFT, pts, s_true + np.array([25.0, -30.0, 10.0, -20.0]))
    np.testing.assert_allclose(got[0], s_true, atol=TOL)  # from the coarse samples
    np.testing.assert_allclose(got[3], s_true, atol=TOL)  # from s_guess


def test_bad_input():
    with pytest.raises(ValueError, match=r"point must have shape \(3,\)"):
        T.project(LEFT, jnp.zeros(2))
    with pytest.raises(ValueError, match=r"point must have shape \(3,\)"):
        T.to_track_coordinates(LEFT, jnp.zeros((2, 3)))
    with pytest.raises(ValueError, match="s_guess must be a scalar"):
        T.project(LEFT, jnp.zeros(3), s_guess=jnp.zeros(2))


# ---------------------------------------------------------------- gradients


def _coordinates(track, p):
    return jnp.stack(T.to_track_coordinates(track, p))


_jac_fwd = jax.jit(jax.vmap(jax.jacfwd(_coordinates, 1), (None, 0)))
_grad_s = jax.jit(jax.vmap(jax.grad(T.project, 1), (None, 0)))


def test_grad_wrt_point():
    s_true = np.array([20.0, LS + 40.0, LS + LT + 100.0, LS + LT + LA + 30.0])
    lat_true = np.array([1.5, -2.0, 1.8, -0.7])
    pts = np.asarray(round_trip(LEFT, s_true, lat_true, np.full(4, 0.4))[0])
    jac = np.asarray(_jac_fwd(LEFT, pad(pts, 8)))[:4]
    grad_s = np.asarray(_grad_s(LEFT, pad(pts, 8)))[:4]  # reverse mode
    np.testing.assert_allclose(grad_s, jac[:, 0, :], atol=1e-13)
    # Central differences, one axis at a time.
    h = 1e-5
    fd = np.zeros((4, 3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        plus, minus = project_all(LEFT, pts + e)[:3], project_all(LEFT, pts - e)[:3]
        fd[:, :, j] = (np.stack(plus, 1) - np.stack(minus, 1)) / (2 * h)
    np.testing.assert_allclose(jac, fd, rtol=0, atol=1e-8)
    # Analytic: ds/dp = t / (1 - kappa * horizontal lateral offset).
    t, kappa, c = project_all(LEFT, pts)[4:]
    n0 = np.stack([-t[:, 1], t[:, 0], np.zeros(4)], 1)
    lateral_h = np.sum((pts - c) * n0, axis=1)
    np.testing.assert_allclose(grad_s, t / (1 - kappa * lateral_h)[:, None], atol=1e-12)
    assert np.max(np.abs(kappa * lateral_h)) > 1e-3  # the curvature term matters here


def _s_of_fixed_point(radius):
    track = make_curve("left", radius)
    return T.project(track, jnp.array([LS + LT + 50.0, 40.0, 0.2]), s_guess=LS + LT + 60.0)


def test_grad_wrt_radius_through_projection():
    # One compiled function: values at R +- h for central differences, grad at R.
    h = 1e-2
    values, grads = jax.jit(jax.vmap(jax.value_and_grad(_s_of_fixed_point)))(
        jnp.array([R + h, R - h, R])
    )
    fd = (values[0] - values[1]) / (2 * h)
    assert float(grads[2]) == pytest.approx(float(fd), rel=1e-6)
    assert abs(float(fd)) > 1e-3


def _carried_and_evaluated(track, p):
    s, centre, (ch, sh) = T.project_onto_centreline(track, p)
    return (s, centre, jnp.stack([ch, sh]), T.centreline_position(track, s),
            T.track_frame(track, s)[:2, 0])


_carried_v = jax.jit(jax.vmap(_carried_and_evaluated, (None, 0)))


@pytest.mark.parametrize("track", [LEFT, RIGHT], ids=["left", "right"])
def test_the_centreline_carried_by_the_last_step_is_the_one_at_s(track):
    # the last Newton step's centreline, moved to first order by the step, against a
    # new evaluation at the projected s (round trips place the points)
    s, lat, vert = sample_points(TOTAL, k=N // 2)
    points = round_trip(track, s, lat, vert)[0]
    out = [np.asarray(o[:len(s)]) for o in _carried_v(track, pad(points))]
    _, carried, tangent, centre, evaluated = out
    np.testing.assert_allclose(carried, centre, rtol=0, atol=2e-13)
    np.testing.assert_allclose(tangent, evaluated, rtol=0, atol=2e-15)


def _rail_origin_height(track, p):
    """The rail section's origin under p, by the carried centreline and by a new
    evaluation of the rail frame at its s, dotted with a fixed vector."""
    s, origin, axes = T.rail_under_wheel(track, p, 1.0)
    direct = T.rail_frame(track, s, 1.0)
    weights = jnp.array([0.3, 0.5, 0.7])
    return jnp.stack([origin @ weights, direct[0] @ weights, axes[:, 2] @ weights,
                      direct[1][:, 2] @ weights])


def test_rail_under_wheel_matches_the_rail_frame_at_its_section_with_gradients():
    p = np.asarray(round_trip(LEFT, np.array([LS + LT + 60.0]), np.array([0.75]),
                              np.array([0.1]))[0][0])
    values = np.asarray(jax.jit(_rail_origin_height)(LEFT, p))
    np.testing.assert_allclose(values[0], values[1], rtol=0, atol=1e-13)
    np.testing.assert_allclose(values[2], values[3], rtol=0, atol=1e-15)
    reverse = np.asarray(jax.jit(jax.jacrev(_rail_origin_height, 1))(LEFT, p))
    forward = np.asarray(jax.jit(jax.jacfwd(_rail_origin_height, 1))(LEFT, p))
    h = 1e-5
    central = np.stack([(np.asarray(_rail_origin_height(LEFT, p + h * e))
                         - np.asarray(_rail_origin_height(LEFT, p - h * e))) / (2 * h)
                        for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(forward, reverse, rtol=0, atol=1e-13)
    np.testing.assert_allclose(reverse, central, rtol=0, atol=1e-5)
    np.testing.assert_allclose(reverse[0], reverse[1], rtol=0, atol=1e-12)
