"""The wear per km in steady curving and its gradient by the implicit function theorem
(:func:`jaxrail.wear.steady.steady_wear`) against central differences of the steady
state itself: the suspended wheelset with a 1:40 conical wheel in a 1000 m left curve
(tests/stability/test_curving.py's vehicle), the KTH map."""

import numpy as np
import pytest

from jaxrail.profiles.analytic import conical_wheel
from jaxrail.track import Track
from jaxrail.track.layout import Arc
from jaxrail.vehicles import get_values, set_values
from jaxrail.vehicles.suspended_wheelset import suspended_wheelset
from jaxrail.wear import ArchardKTH
from jaxrail.wear.steady import steady_wear

RADIUS = 1000.0  # [m]
SPEED = 20.0  # [m/s]
NAMES = ("primary_longitudinal_stiffness", "friction")
RELATIVE_STEP = 1e-4
FD_RTOL = 1e-3


@pytest.fixture(scope="module")
def steady():
    vehicle, params = suspended_wheelset(conical_wheel(0.025, nominal_radius=0.46),
                                         curve_radius=RADIUS)
    track = Track.from_segments([Arc(300.0, RADIUS, "left")])
    return vehicle, params, steady_wear(vehicle, params, track, ArchardKTH(), NAMES)


def test_steady_wear_gradient_against_central_differences(steady):
    vehicle, params, wear = steady
    point = wear(SPEED)
    assert point.wear_number_n.shape == (1, 2) and np.all(point.wear_number_n > 0.0)
    values = np.asarray(get_values(vehicle, params, NAMES))
    for k, name in enumerate(NAMES):
        h = RELATIVE_STEP * values[k]
        sides = [wear(SPEED, set_values(vehicle, params, [name], [values[k] + s * h]),
                      start=point.state).wear_number_n for s in (1.0, -1.0)]
        central = (sides[0] - sides[1]) / (2.0 * h)
        assert np.max(np.abs(central * values[k])) > 1e-3 * np.max(point.wear_number_n)
        np.testing.assert_allclose(point.gradient[name], central, rtol=FD_RTOL,
                                   err_msg=name)
