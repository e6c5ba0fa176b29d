"""Track layout: segment arrays, signed curvature and cant, validation errors."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail import track as T

R, LT, LA, LS = 500.0, 120.0, 300.0, 100.0  # radius, transition, arc, straight [m]
CANT = 0.150  # m


def curve(radius=R, direction="left", cant=CANT):
    return T.Track.from_segments(T.curve_layout(radius, direction, cant, LS, LT, LA, LS))


def test_curve_layout_segments():
    segs = T.curve_layout(R, "right", CANT, LS, LT, LA, 80.0)
    assert [type(s) for s in segs] == [T.Straight, T.Transition, T.Arc, T.Transition, T.Straight]
    arc = segs[2]
    assert (arc.radius, arc.direction, arc.cant, arc.length) == (R, "right", CANT, LA)
    assert (segs[0].length, segs[1].length, segs[3].length, segs[4].length) == (LS, LT, LT, 80.0)


def test_curve_track_arrays():
    track = curve()
    assert track.n_segments == 5
    assert track.kinds == ("straight", "transition", "arc", "transition", "straight")
    starts = [0, LS, LS + LT, LS + LT + LA, LS + 2 * LT + LA]
    np.testing.assert_allclose(track.segment_start, starts)
    np.testing.assert_allclose(track.segment_length, [LS, LT, LA, LT, LS])
    assert float(track.total_length) == 2 * LS + 2 * LT + LA
    np.testing.assert_allclose(track.curvature_start, [0, 0, 1 / R, 1 / R, 0], rtol=1e-15)
    np.testing.assert_allclose(
        track.curvature_rate, [0, 1 / (R * LT), 0, -1 / (R * LT), 0], rtol=1e-15
    )
    np.testing.assert_allclose(track.superelevation_start, [0, 0, CANT, CANT, 0], rtol=1e-15)
    np.testing.assert_allclose(
        track.superelevation_rate, [0, CANT / LT, 0, -CANT / LT, 0], rtol=1e-15
    )
    half = LT / (2 * R)  # heading change of a transition
    np.testing.assert_allclose(
        track.heading_start, [0, 0, half, half + LA / R, 2 * half + LA / R], rtol=1e-15
    )
    assert float(track.rail_centre_distance) == 1.5
    for leaf in jax.tree.leaves(track):
        assert leaf.dtype == jnp.float64
    # Coarse samples: 17 per segment, segment ends included.
    assert track.sample_s.shape == (5 * 17,) and track.sample_xy.shape == (5 * 17, 2)
    np.testing.assert_allclose(track.sample_s[::17], track.segment_start)
    np.testing.assert_allclose(track.sample_xy[::17, 0], track.x_start)
    np.testing.assert_allclose(track.sample_xy[::17, 1], track.y_start)
    np.testing.assert_allclose(track.sample_s[-1], track.total_length)
    heading = jax.vmap(lambda s: T.heading(track, s))(track.sample_s)
    np.testing.assert_allclose(track.sample_tangent,
                               np.stack([np.cos(heading), np.sin(heading)], 1), rtol=0, atol=1e-15)


def test_right_curve_has_negative_curvature_and_cant():
    track = curve(direction="right")
    np.testing.assert_allclose(track.curvature_start, [0, 0, -1 / R, -1 / R, 0], rtol=1e-15)
    np.testing.assert_allclose(track.superelevation_start, [0, 0, -CANT, -CANT, 0], rtol=1e-15)
    assert float(track.heading_start[-1]) == pytest.approx(-(LT + LA) / R, rel=1e-15)
    assert float(track.y_start[-1]) < 0.0 < float(curve().y_start[-1])


def test_start_pose_and_first_segment_start():
    track = T.Track.from_segments([T.Straight(10.0), T.Straight(5.0)], start=(3.0, 4.0, np.pi / 2))
    np.testing.assert_allclose(track.x_start, [3.0, 3.0], atol=1e-14)
    np.testing.assert_allclose(track.y_start, [4.0, 14.0], atol=1e-14)
    np.testing.assert_allclose(track.heading_start, [np.pi / 2, np.pi / 2])


def test_reverse_and_compound_curves():
    r1, r2 = 400.0, 600.0
    reverse = T.Track.from_segments(
        [T.Arc(50.0, r1, "left", 0.1), T.Transition(80.0), T.Arc(50.0, r2, "right", 0.05)]
    )
    np.testing.assert_allclose(reverse.curvature_rate[1], (-1 / r2 - 1 / r1) / 80.0, rtol=1e-14)
    np.testing.assert_allclose(reverse.superelevation_rate[1], (-0.05 - 0.1) / 80.0, rtol=1e-14)
    compound = T.Track.from_segments(
        [T.Arc(50.0, r1, "left"), T.Transition(80.0), T.Arc(50.0, r2, "left")]
    )
    np.testing.assert_allclose(compound.curvature_rate[1], (1 / r2 - 1 / r1) / 80.0, rtol=1e-14)


def test_straight_track():
    track = T.straight_track(250.0, start=(1.0, 2.0, 0.3), rail_centre_distance=1.505)
    assert track.kinds == ("straight",)
    assert float(track.total_length) == 250.0
    pose = [track.x_start[0], track.y_start[0], track.heading_start[0]]
    np.testing.assert_allclose(pose, [1.0, 2.0, 0.3])
    assert float(track.rail_centre_distance) == 1.505


def test_allow_curvature_jumps_accepts_straight_to_arc():
    track = T.Track.from_segments(
        [T.Straight(10.0), T.Arc(20.0, 100.0, "right"), T.Arc(20.0, 50.0, "right")],
        allow_curvature_jumps=True,
    )
    np.testing.assert_allclose(track.curvature_start, [0, -1 / 100, -1 / 50])
    np.testing.assert_allclose(track.heading_start, [0, 0, -0.2], rtol=1e-15)


# ---------------------------------------------------------------- bad input


BAD_LAYOUTS = [
    ([], "empty layout"),
    ([T.Straight(0.0)], r"segments\[0\] \(Straight\): length must be > 0"),
    ([T.Straight(10.0), T.Straight(-5.0)], r"segments\[1\] \(Straight\): length must be > 0"),
    ([T.Arc(0.0, 100.0)], r"segments\[0\] \(Arc\): length must be > 0"),
    ([T.Arc(10.0, 0.0)], r"segments\[0\] \(Arc\): radius must be > 0"),
    ([T.Arc(10.0, -300.0, "right")], r"segments\[0\] \(Arc\): radius must be > 0"),
    ([T.Arc(10.0, 300.0, "up")], r"segments\[0\] \(Arc\): unknown direction 'up'"),
    ([T.Arc(10.0, 300.0, "left", 1.6)], r"segments\[0\] \(Arc\): \|cant\| must be <"),
    ([T.Transition(10.0), T.Straight(10.0)], r"segments\[0\] \(Transition\).*at the start"),
    ([T.Straight(10.0), T.Transition(10.0)], r"segments\[1\] \(Transition\).*at the end"),
    (
        [T.Straight(1.0), T.Transition(0.0), T.Straight(1.0)],
        r"segments\[1\] \(Transition\): length must be > 0",
    ),
    (
        [T.Straight(10.0), T.Transition(10.0), T.Transition(10.0), T.Arc(10.0, 300.0)],
        r"segments\[1\] \(Transition\): neighbour segments\[2\] is also a Transition",
    ),
    (
        [T.Straight(10.0), T.Arc(10.0, 300.0, "left", 0.1)],
        r"discontinuous layout: cant jumps .*segments\[0\] \(Straight\) and segments\[1\] "
        r"\(Arc\); insert a Transition",
    ),
    (
        [T.Straight(10.0), T.Arc(10.0, 300.0)],
        r"discontinuous layout: curvature jumps .*segments\[1\].*insert a Transition",
    ),
    (
        [T.Arc(10.0, 300.0), T.Arc(10.0, 400.0)],
        r"discontinuous layout: curvature jumps from 0.00333.* to 0.0025",
    ),
    (
        [T.Arc(10.0, 300.0, "left"), T.Arc(10.0, 300.0, "right")],
        r"discontinuous layout: curvature jumps",
    ),
    (
        [T.Arc(10.0, 300.0, "left", 0.1), T.Arc(10.0, 300.0, "right", 0.1)],
        r"discontinuous layout: cant jumps from 0.1 m to -0.1 m",
    ),
]


@pytest.mark.parametrize("segments, message", BAD_LAYOUTS)
def test_bad_layouts_raise(segments, message):
    with pytest.raises(ValueError, match=message):
        T.Track.from_segments(segments)


def test_cant_jump_errors_even_when_curvature_jumps_allowed():
    with pytest.raises(ValueError, match="cant jumps are never allowed"):
        T.Track.from_segments(
            [T.Straight(10.0), T.Arc(10.0, 300.0, "left", 0.1)], allow_curvature_jumps=True
        )


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="start must be"):
        T.Track.from_segments([T.Straight(1.0)], start=(0.0, 0.0))
    with pytest.raises(ValueError, match="rail_centre_distance must be > 0"):
        T.Track.from_segments([T.Straight(1.0)], rail_centre_distance=0.0)
    with pytest.raises(ValueError, match="samples_per_segment"):
        T.Track.from_segments([T.Straight(1.0)], samples_per_segment=0)
    with pytest.raises(ValueError, match=r"segments\[0\] \(Straight\).length must be a scalar"):
        T.Track.from_segments([T.Straight(np.ones(2))])
    with pytest.raises(TypeError, match=r"segments\[1\] must be Straight, Arc or Transition"):
        T.Track.from_segments([T.Straight(1.0), (1.0, 2.0)])
    # Cant is limited by the rail-centre distance actually given.
    with pytest.raises(ValueError, match=r"\|cant\| must be < rail_centre_distance = 0.1"):
        T.Track.from_segments([T.Arc(10.0, 300.0, "left", 0.15)], rail_centre_distance=0.1)


# ---------------------------------------------------------------- traced parameters


def _built(params):
    radius, cant = params
    track = curve(radius, "left", cant)
    return jnp.stack([track.heading_start[-1], track.x_start[-1], track.y_start[-1],
                      track.superelevation_rate[1], track.curvature_rate[1]])


def test_build_inside_jit_grad_and_vmap():
    x = jnp.array([R, CANT])
    eager = curve()
    values = jax.jit(_built)(x)
    np.testing.assert_allclose(
        values,
        [eager.heading_start[-1], eager.x_start[-1], eager.y_start[-1],
         eager.superelevation_rate[1], eager.curvature_rate[1]],
        rtol=1e-14,
    )
    jac = jax.jit(jax.jacrev(_built))(x)
    # Analytic: heading (LT + LA) / R; cant rate cant / LT; curvature rate 1 / (R LT).
    assert float(jac[0, 0]) == pytest.approx(-(LT + LA) / R**2, rel=1e-12)
    assert float(jac[3, 1]) == pytest.approx(1 / LT, rel=1e-12)
    assert float(jac[4, 0]) == pytest.approx(-1 / (R**2 * LT), rel=1e-12)
    h = 1e-2
    batch = jax.jit(jax.vmap(_built))(jnp.array([[R + h, CANT], [R - h, CANT]]))
    np.testing.assert_allclose(jac[1:3, 0], (batch[0, 1:3] - batch[1, 1:3]) / (2 * h), rtol=1e-7)
    assert abs(float(jac[2, 0])) > 0.01


def test_structural_checks_run_under_jit():
    def bad(radius):
        return T.Track.from_segments([T.Straight(10.0), T.Arc(10.0, radius)]).x_start

    with pytest.raises(ValueError, match="discontinuous layout: curvature jumps"):
        jax.jit(bad)(300.0)
