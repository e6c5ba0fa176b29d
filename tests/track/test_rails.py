"""The rail under a wheel (:mod:`jaxrail.track.rails`): a flexible track's deflection is
an argument that moves the rail along the canted n and b on top of the irregularity,
and a wheel's height over its rail goes through the same rail."""

import numpy as np
import pytest

from jaxrail.track import Irregularity, Rails, rail_frame, standard_rails, straight_track
from jaxrail.track.rails import HALF_TAPING_DISTANCE, rail_under_wheel, wheel_height

OFFSET = 0.75
A, V, C, G = 2e-3, -1e-3, 0.6e-3, 0.8e-3
RAILS = Rails(standard_rails().profile, OFFSET)


def _irregular():
    irregularity = Irregularity(np.tile([A, V, C, G], (4, 1)), 0.0, 10.0)
    return straight_track(40.0, rails=RAILS).with_irregularity(irregularity)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_the_deflection_moves_the_rail_along_n_and_b_on_top_of_the_irregularity(side):
    track, deflection = _irregular(), np.array([3e-5, -9e-4])
    rigid, frame = rail_frame(track, 12.0, side)
    moved, moved_frame = rail_frame(track, 12.0, side, deflection)
    np.testing.assert_allclose(np.asarray(moved - rigid), [0.0, *deflection], atol=1e-15)
    np.testing.assert_array_equal(np.asarray(moved_frame), np.asarray(frame))
    origin = np.asarray(rigid) + np.array([0.0, 0.0, 0.1])
    s, under, _ = rail_under_wheel(track, origin, side, deflection=deflection)
    assert float(s) == pytest.approx(12.0, abs=1e-12)
    np.testing.assert_array_equal(np.asarray(under), np.asarray(moved))


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_wheel_height_is_over_its_irregular_deflected_rail(side):
    track, deflection = _irregular(), np.array([3e-5, -9e-4])
    position, rotation = np.array([12.0, 0.0, 0.45]), np.eye(3)
    assert HALF_TAPING_DISTANCE == OFFSET  # the wheel origin right above the rail's
    ideal = float(wheel_height(straight_track(40.0, rails=RAILS), position, rotation, side))
    assert ideal == pytest.approx(0.45, abs=1e-15)
    irregular = float(wheel_height(track, position, rotation, side))
    assert irregular == pytest.approx(0.45 - (V + side * C / 2), abs=1e-15)
    deflected = float(wheel_height(track, position, rotation, side, deflection))
    assert deflected == pytest.approx(irregular - deflection[1], abs=1e-15)


def test_every_track_has_the_standard_rails_unless_given():
    from jaxrail.profiles import rail_offset, uic60

    rails = standard_rails()
    assert rails.profile.name == "UIC60 1:40"
    assert float(rails.offset) == float(rail_offset(uic60("1:40"), 1.435))
    assert float(rails.gauge) == pytest.approx(1.435, abs=1e-15)
    assert straight_track(10.0).rails is rails
    wide = straight_track(10.0).with_rails(Rails.at_gauge(uic60("1:40"), 1.445))
    assert float(wide.rails.gauge) == pytest.approx(1.445, abs=1e-15)
    assert float(wide.rails.offset) == pytest.approx(float(rails.offset) + 0.005, abs=1e-15)
    with pytest.raises(TypeError, match="rails must be Rails"):
        straight_track(10.0).with_rails(OFFSET)


def test_a_wheel_height_from_its_wheelsets_arc_length_is_the_one_from_the_nearest_sample():
    """The stop event's and outputs' wheel heights start the projection at the wheelset's
    arc length (one Newton step and the last): on a canted curve with transitions, for
    wheelsets yawed up to 50 mrad and 30 mm off the centre line (in the straights, the
    transitions and the arc, at the joints and beyond the ends), the heights and their
    derivatives by the wheelset's position are those from the nearest sample."""
    import jax
    import jax.numpy as jnp

    from jaxrail.track import (Track, centreline_position, curve_layout, to_track_coordinates,
                               track_frame)

    track = Track.from_segments(curve_layout(300.0, "left", 0.15, 50.0, 80.0, 200.0, 50.0))
    rng = np.random.default_rng(3)
    s = np.concatenate([[-5.0, 0.0, 50.0, 130.0, 330.0, 410.0, 465.0],
                        rng.uniform(0.0, 460.0, 25)])
    lateral, yaw = rng.uniform(-0.03, 0.03, s.size), rng.uniform(-0.05, 0.05, s.size)
    yaw[:4] = [0.05, -0.05, 0.05, -0.05]

    def heights(s, lateral, yaw, side):
        frame = track_frame(track, s)
        turn = jnp.array([[jnp.cos(yaw), -jnp.sin(yaw), 0.0], [jnp.sin(yaw), jnp.cos(yaw), 0.0],
                          [0.0, 0.0, 1.0]])
        rotation = frame @ turn
        position = centreline_position(track, s) + lateral * frame[:, 1] + 0.45 * frame[:, 2]

        def both(position):
            s_wheelset = to_track_coordinates(track, position)[0]  # as the outputs
            return jnp.stack([wheel_height(track, position, rotation, side),
                              wheel_height(track, position, rotation, side,
                                           s_guess=s_wheelset)])
        return both(position), jax.jacfwd(both)(position), jax.jacrev(both)(position)

    for side in (1.0, -1.0):
        value, forward, reverse = jax.jit(jax.vmap(lambda *a: heights(*a, side)))(s, lateral,
                                                                                  yaw)
        value, forward, reverse = np.asarray(value), np.asarray(forward), np.asarray(reverse)
        assert np.all(np.abs(value[:, 0] - 0.45) < 0.05)  # the wheels near their rails
        np.testing.assert_allclose(value[:, 1], value[:, 0], rtol=0, atol=1e-12)
        # the derivatives within kappa x the last step (under 1e-7 m from the wheelset's
        # arc length, under 1e-12 m from the sample) of the carried centreline's
        np.testing.assert_allclose(forward[:, 1], forward[:, 0], rtol=0, atol=1e-11)
        np.testing.assert_allclose(reverse[:, 1], reverse[:, 0], rtol=0, atol=1e-11)
