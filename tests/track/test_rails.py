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
