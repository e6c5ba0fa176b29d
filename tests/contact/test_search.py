"""The paper's contact search: analytic cases, eqs. (12)-(13) corrected, penetration,
lift-off, sub-strip refinement, gradients, vmap."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact import SearchConfig, search_vehicle, search_wheelset, wheelset_pose
from jaxrail.contact.search import _surface_deepest, _wheel_geometry
from jaxrail.contact.strip import longitudinal_offset, wheel_frame
from jaxrail.profiles import s1002
from jaxrail.profiles.analytic import CircularProfile, conical_wheel
from jaxrail.profiles.measures import rail_offset
from jaxrail.profiles.uic60 import uic60
from jaxrail.track import Rails, rail_frame, straight_track

STATION = 10.0
WHEEL, RAIL = s1002(), uic60()
OFFSET = float(rail_offset(RAIL))
TRACK = straight_track(20.0, rails=Rails(RAIL, OFFSET))


@jax.jit
def real_search(lateral, vertical, roll, yaw):
    position, rotation = wheelset_pose(TRACK, STATION, lateral, vertical, roll, yaw)
    return search_wheelset(WHEEL, TRACK, position, rotation, SearchConfig(), STATION)


def touching_height(lateral, roll=0.0, yaw=0.0):
    """Wheelset height at which the deepest wheel just touches (bisection)."""
    lo, hi = 0.455, 0.47
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        deepest = float(jnp.max(real_search(lateral, mid, roll, yaw).penetration))
        lo, hi = (mid, hi) if deepest > 0.0 else (lo, mid)
    return hi


CONE, HEAD = 0.05, 0.3  # cone slope [-] and head radius [m] of the analytic case
CONE_POINT = -HEAD * np.sin(CONE)  # u_r = u_w of the tangent point [m]


def coned_wheel_on_circular_head(lowered):
    """Both wheels of a coned wheelset lowered by ``lowered`` [m] from touching a
    circular head: the contact patches."""
    wheel, rail = conical_wheel(CONE), CircularProfile(HEAD, half_width=0.03)
    touching = 0.46 + np.tan(CONE) * HEAD * np.sin(CONE) - HEAD * (1.0 - np.cos(CONE))
    position, rotation = wheelset_pose(TRACK, STATION, 0.0, touching - lowered, 0.0, 0.0)
    track = TRACK.with_rails(Rails(rail, 0.75))
    return jax.jit(search_wheelset)(wheel, track, position, rotation, SearchConfig(), STATION)


def test_coned_wheel_on_circular_head_analytic():
    """Cone angle g on a circular head of radius R: the contact lies where the head's
    slope equals the cone's, u_r = -R sin(g), with contact angle g; lowering the
    wheelset by d from touching gives the normal penetration d cos(g) exactly."""
    cone, head, u, lowered = CONE, HEAD, CONE_POINT, 1e-6
    out = coned_wheel_on_circular_head(lowered)
    assert out.active[:, 0].tolist() == [True, True]
    assert not bool(jnp.any(out.active[:, 1:]))
    np.testing.assert_allclose(out.penetration[:, 0], lowered * np.cos(cone), rtol=1e-7)
    np.testing.assert_allclose(out.y_rail[:, 0], u, atol=1e-9)
    np.testing.assert_allclose(out.y_wheel[:, 0], u, atol=1e-7)
    np.testing.assert_allclose(out.contact_angle[:, 0], cone, atol=1e-8)
    np.testing.assert_allclose(out.rolling_radius[:, 0], 0.46 - np.tan(cone) * u, atol=1e-9)
    np.testing.assert_allclose(out.curvature_rail_y[:, 0], 1.0 / head, rtol=1e-8)
    np.testing.assert_allclose(out.curvature_wheel_y[:, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(out.curvature_contact_y[:, 0], 1.0 / head, rtol=1e-3)  # secant, narrow
    np.testing.assert_allclose(out.y_track[:, 0], [0.75 + u, -(0.75 + u)], atol=1e-9)
    np.testing.assert_allclose(out.normal[0, 0], [0.0, -np.sin(cone), np.cos(cone)], atol=1e-9)
    np.testing.assert_allclose(out.normal[1, 0], [0.0, np.sin(cone), np.cos(cone)], atol=1e-9)


def test_wide_patch_on_circular_head_acts_at_its_centre():
    """The same cone pressed 0.1 mm into the head: an interpenetration about 15 mm wide,
    symmetric about the tangent point, whose centre is that point and whose overlap
    curvature is the head's 1/R (the gap is a circle, nearly a parabola). The centre is
    integrated piecewise linearly between strips 1 mm apart: within 0.01 mm."""
    out = coned_wheel_on_circular_head(1e-4)
    np.testing.assert_allclose(out.penetration[:, 0], 1e-4 * np.cos(CONE), rtol=1e-6)
    np.testing.assert_allclose(out.y_wheel[:, 0], CONE_POINT, atol=1e-5)
    np.testing.assert_allclose(out.curvature_contact_y[:, 0], 1.0 / HEAD, rtol=0.02)


def test_corrected_eq12_and_eq13_with_yaw():
    """With yaw, the wheel normal at s_w (eq. 12 with the slope F') is perpendicular to
    the rail tangent, and the contact's longitudinal offset equals eq. (13) with F',
    not the OCR's form with F."""
    yaw = 0.01
    out = real_search(2e-3, touching_height(2e-3, yaw=yaw) - 2e-5, 0.0, yaw)
    position, rotation = wheelset_pose(TRACK, STATION, 2e-3, 0.46, 0.0, yaw)
    surface = WHEEL.surfaces[0]
    for side, k in ((1.0, 0), (-1.0, 1)):
        _, axes = rail_frame(TRACK, float(out.s_rail[k, 0]), side)
        frame = wheel_frame(rotation[:, 1], axes[:, 0])
        y = out.y_wheel[k, 0]
        radius, slope = 0.46 + surface.height(y), surface.slope(y)
        expected = longitudinal_offset(y, radius, slope, frame, side)
        assert float(out.dx[k, 0]) == pytest.approx(float(expected), abs=1e-10)
        ocr = side * (jnp.abs(radius) * surface.height(y) - y) * frame.sin_alpha
        assert abs(float(out.dx[k, 0]) - float(ocr)) > 1e-5
        # Independent normal: cross product of the surface's tangents by autodiff.
        def point(y_w, theta):
            radial = -jnp.cos(theta) * frame.up + jnp.sin(theta) * frame.forward
            return side * y_w * frame.axle + (0.46 + surface.height(y_w)) * radial
        t_y = jax.jacfwd(point, 0)(y, out.s_wheel[k, 0])
        t_theta = jax.jacfwd(point, 1)(y, out.s_wheel[k, 0])
        normal = jnp.cross(t_y, t_theta)
        assert abs(float(normal @ axes[:, 0] / jnp.linalg.norm(normal))) < 1e-12
        assert abs(float(out.dx[k, 0])) > 1e-5  # yaw really moves the contact point


def test_lowering_gives_penetration_d_cos_gamma():
    """One patch (left wheel 2 mm toward its flange, away from the two-point contacts
    at 0 and ~4.7 mm): lowering by d gives the penetration d cos(contact angle)."""
    height = touching_height(2e-3)
    d = 5e-5
    out = real_search(2e-3, height - d, 0.0, 0.0)
    assert list(np.asarray(out.active[0])) == [True, False, False]
    gamma = out.contact_angle[0, 0]
    assert float(out.penetration[0, 0]) == pytest.approx(d * np.cos(gamma), rel=2e-3)


def test_two_point_contact_hands_over_continuously():
    """Centred S1002 on UIC60 1:40 is a two-point contact (tread at -7 mm and +3 mm):
    through it, the deepest point of the left wheel jumps by 10 mm, but the patches share
    the load and each sits at the centre of its interpenetration, so the total
    penetration^1.5 and the load-weighted contact position change by O(step): halving
    the step halves the largest change. Wheelset pressed 50 um into the rails at a
    fixed height."""
    height = touching_height(0.0) - 5e-5

    @jax.jit
    def sweep(laterals):
        def one(lateral):
            position, rotation = wheelset_pose(TRACK, STATION, lateral, height, 0.0, 0.0)
            _, geometry = _wheel_geometry(TRACK, position, rotation, 1.0, STATION)
            _, y_deepest = _surface_deepest(WHEEL.surfaces[0], WHEEL, RAIL, geometry, SearchConfig())
            return real_search(lateral, height, 0.0, 0.0), y_deepest

        out, y_deepest = jax.vmap(one)(laterals)
        load = out.penetration[:, 0] ** 1.5
        total = jnp.sum(load, axis=1)
        position = jnp.sum(load * out.y_wheel[:, 0], axis=1) / total
        return total, position, y_deepest, jnp.sum(out.active[:, 0], axis=1)

    coarse, y_coarse, deepest, count = (np.asarray(a) for a in sweep(jnp.linspace(-0.4e-3, 0.4e-3, 41)))
    fine, y_fine, _, _ = (np.asarray(a) for a in sweep(jnp.linspace(-0.4e-3, 0.4e-3, 81)))
    assert np.max(np.abs(np.diff(deepest))) > 5e-3  # the deepest point does jump
    assert count.max() == 2 and count.min() == 1  # a second patch appears on the way
    assert np.max(np.abs(np.diff(fine))) < 0.6 * np.max(np.abs(np.diff(coarse)))
    assert np.max(np.abs(np.diff(y_fine))) < 0.6 * np.max(np.abs(np.diff(y_coarse)))


def _weighted_outputs(pose, weights):
    """A scalar of the search's outputs at a pose (lateral, vertical, roll, yaw)."""
    out = real_search(pose[0], pose[1], pose[2], pose[3])
    values = jnp.stack([out.penetration[0, 0], out.penetration[1, 0], out.y_wheel[0, 0],
                        out.y_rail[1, 0], out.dx[0, 0], jnp.sum(out.penetration)])
    return values @ weights


weighted_gradient = jax.jit(jax.grad(_weighted_outputs))  # one reverse-mode compile


def test_lift_off_clears_mask_with_finite_gradients():
    out = real_search(0.0, 0.4625, 0.0, 0.0)
    assert not bool(jnp.any(out.active))
    assert float(jnp.max(out.penetration)) == 0.0
    weights = jnp.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    gradient = weighted_gradient(jnp.array([0.0, 0.4625, 0.0, 0.0]), weights)
    assert np.all(np.isfinite(gradient)) and np.all(np.asarray(gradient) == 0.0)


def test_sub_strip_refinement_is_continuous_and_accurate():
    """The left wheel's contact moves continuously with the shift (not in strip steps)
    and agrees with a 10x finer strip grid to 0.025 mm. The patch is wide (the centre of
    its interpenetration, integrated piecewise linearly between strips, whose bias on
    the curved S1002 tread is about 2 % of the spacing)."""
    shifts = np.linspace(0.5e-3, 4e-3, 16)  # between the jumps at 0 and ~4.7 mm
    height = touching_height(0.0) - 2e-5
    fine = SearchConfig(strip_spacing=1e-4)

    @jax.jit
    def both(lateral):
        position, rotation = wheelset_pose(TRACK, STATION, lateral, height, 0.0, 0.0)
        coarse = search_wheelset(WHEEL, TRACK, position, rotation, SearchConfig(), STATION)
        dense = search_wheelset(WHEEL, TRACK, position, rotation, fine, STATION)
        return coarse.y_wheel[0, 0], dense.y_wheel[0, 0], coarse.active[0, 0], dense.active[0, 0]

    coarse, dense, on_coarse, on_dense = (np.asarray(a) for a in jax.lax.map(both, jnp.asarray(shifts)))
    assert on_coarse.all() and on_dense.all()
    np.testing.assert_allclose(coarse, dense, atol=2.5e-5)
    steps = np.diff(coarse)  # the fine grid's increments, not jumps between strips 1 mm apart
    assert np.all(steps < 0.0) and np.max(np.abs(steps - np.diff(dense))) < 0.03e-3


def test_gradients_against_finite_differences():
    """Penetrations, contact positions and the longitudinal offset: reverse-mode
    gradients with respect to the pose against central differences."""
    height = touching_height(1e-3) - 3e-5
    pose = jnp.array([1e-3, height, 2e-4, 3e-3])
    steps = np.array([1e-7, 1e-8, 1e-7, 1e-6])
    for output in range(5):
        weights = jnp.zeros(6).at[output].set(1.0)
        gradient = np.asarray(weighted_gradient(pose, weights))
        assert np.all(np.isfinite(gradient))
        for j, h in enumerate(steps):
            e = np.zeros(4)
            e[j] = h
            fd = float(_weighted_outputs(pose + e, weights) - _weighted_outputs(pose - e, weights)) / (2 * h)
            assert gradient[j] == pytest.approx(fd, rel=2e-3, abs=1e-9 + 1e-4 * abs(fd)), (output, j)


def test_vehicle_vmap_equals_loop():
    laterals = jnp.array([0.0, 1e-3, -2e-3, 4e-3])
    heights = jnp.array([0.46, 0.4599, 0.4598, 0.4599])
    yaws = jnp.array([0.0, 1e-3, -2e-3, 0.0])
    poses = [wheelset_pose(TRACK, STATION - 2.0 * k, laterals[k], heights[k], 0.0, yaws[k]) for k in range(4)]
    positions = jnp.stack([p for p, _ in poses])
    rotations = jnp.stack([r for _, r in poses])
    batched = jax.jit(search_vehicle)(WHEEL, TRACK, positions, rotations)
    for k in range(4):
        single = jax.jit(search_wheelset)(WHEEL, TRACK, positions[k], rotations[k])
        for field in ("penetration", "y_wheel", "y_rail", "dx", "normal", "active"):
            np.testing.assert_allclose(getattr(batched, field)[k], getattr(single, field), atol=1e-12)
