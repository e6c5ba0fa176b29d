"""The gradient of wear through a run (forward mode, one tangent per parameter) against
central differences of the same runs (in friction the slope fitted through 1, 2 and 3
steps either side): the bogie entering a 300 m curve
(``bogie-curve-entry``, fixed steps, its leading outer wheel on the flange root from 0.6
s), the wear volume per km counted from 0.5 s, in the primary longitudinal stiffness, the
friction and the wheelbase."""

import numpy as np
import pytest

from jaxrail.scenarios import load_scenario
from jaxrail.wear import ArchardKTH, wear_gradient

NAMES = ("primary_longitudinal_stiffness", "friction", "wheelbase")
# of each parameter's value: the wear of this 0.5 s of curve entry is rough at relative
# scales of 1e-4 and more (central differences there differ from each other in size and
# sign: docs/wear.md, "The gradient of wear"); at 1e-5 they are near the local derivative.
# There the compiler's rounding sets a floor: the run's wear moves by about 1.4e-8 of
# itself with XLA's options, which moves a central difference by that over the step and
# the parameter's elasticity: 1e-3 of the derivative in friction (elasticity -1.5), 7e-5
# and 2e-5 in the stiffness (-19) and the wheelbase (-74). So friction's is the slope
# fitted through 1, 2 and 3 steps either side (central differences weighted by their
# step squared: 3.7 times less noise; its ripple is wider than 3 steps); the wheelbase's
# ripple shows from 2 steps (-13124, -8856, -5264 at 1, 2, 3), so the others take 1.
RELATIVE_STEP = 1e-5
STEPS = {"friction": (1, 2, 3)}
FD_RTOL = 1e-3
T_FROM = 0.5  # [s]
# its eleven forward-mode runs take 700 s at the suite's LLVM level 0 (each 45-50 s after a
# 170 s compile), 16 s each at full optimisation
pytestmark = pytest.mark.usefixtures("integrations_at_level_1")


@pytest.fixture(scope="module")
def gradient():
    scenario = load_scenario("bogie-curve-entry")
    built = scenario.build()
    model = scenario.contact_model(*built)
    law = ArchardKTH()

    def at(values=None):
        return wear_gradient(scenario, NAMES, law, t_from=T_FROM, built=built, model=model,
                             values=values)
    return at


def _totals(g):
    """The bogie's total wear per km and its flange part [mm^3/km], and their
    derivatives (k,)."""
    return (g.volume_per_km.sum(), g.flange_per_km.sum(),
            g.d_volume_per_km.sum(axis=(0, 1)), g.d_flange_per_km.sum(axis=(0, 1)))


def test_wear_gradient_against_central_differences(gradient):
    g = gradient()
    volume, flange, d_volume, d_flange = _totals(g)
    assert volume > 0.0
    # the leading outer wheel runs on its flange root (about 30 degrees), below the 0.6
    # rad that counts as flange: no flange wear here, and none of its derivatives
    assert flange == 0.0 and np.all(d_flange == 0.0)
    for i, name in enumerate(NAMES):
        h = RELATIVE_STEP * g.values[i]
        central = []
        steps = STEPS.get(name, (1,))
        for k in steps:
            step = np.eye(len(NAMES))[i] * k * h
            plus, minus = _totals(gradient(g.values + step)), _totals(gradient(g.values - step))
            central.append((plus[0] - minus[0]) / (2.0 * k * h))
        weights = np.square(steps)
        fd_volume = np.sum(weights * np.array(central)) / np.sum(weights)
        assert d_volume[i] == pytest.approx(fd_volume, rel=FD_RTOL), (name, central)
        # a derivative that matters: at least 1e-2 of the wear per unit relative change
        assert abs(d_volume[i] * g.values[i]) > 1e-2 * volume, name
