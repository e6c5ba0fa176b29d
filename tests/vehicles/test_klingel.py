"""A free coned wheelset (multibody + contact search + Hertz + eq. 17 + Polach, run by
jaxrail.simulation) hunts with Klingel's kinematic wavelength 2 pi sqrt(r0 e / tan(gamma)) at low speed.

Run with IMEX. Tsit5 is checked against IMEX on the trailer
(tests/vehicles/test_trailer.py); here its steps, about 0.3 ms held by the Hertz
stiffness, would make the 4 s run cost about 80 s of the suite."""

import numpy as np

from jaxrail.profiles.analytic import conical_wheel
from jaxrail.track import straight_track
from jaxrail.simulation import simulate_single_wheelset


def test_klingel_wavelength_within_5_percent():
    cone, speed, distance = 0.05, 5.0, 20.0
    wheel = conical_wheel(cone)
    t1 = distance / speed
    result, (_, patches) = simulate_single_wheelset(
        wheel, straight_track(50.0), speed, 2e-3, t1, n_outputs=801, integrator="imex")
    assert result.status == "successful"
    q = np.asarray(result.q)
    assert np.all(np.isfinite(q))
    x, y = q[:, 0], q[:, 1]
    crossings = [x[k] - y[k] * (x[k + 1] - x[k]) / (y[k + 1] - y[k])
                 for k in range(len(y) - 1) if (y[k] > 0.0) != (y[k + 1] > 0.0)]
    assert len(crossings) >= 2  # down at a quarter, up at three quarters of a wavelength
    measured = 2.0 * (crossings[1] - crossings[0])
    radius, e = float(patches.rolling_radius[0, 0]), float(patches.y_track[0, 0])
    klingel = 2 * np.pi * np.sqrt(radius * e / np.tan(cone))
    assert abs(measured / klingel - 1.0) < 0.05
    assert np.max(np.abs(y)) < 2.5e-3  # neutral kinematic oscillation, no flange contact
