"""Physical inputs given from Python outside their range: a ValueError naming them
(they gave NaN, inf or silently wrong forces), while traced values pass unchecked."""

import jax
import numpy as np
import pytest

from jaxrail.contact import hertz, hertz_stiffness, polach
from jaxrail.contact.normal import Flores, HuntCrossley

BAD_INPUTS = [
    (lambda: hertz(1e4, 1.0, 1.0, nu=-2.0), "hertz: Poisson's ratio nu must lie in (-1.0, 0.5]"),
    (lambda: hertz(1e4, 1.0, 1.0, nu=1.0), "hertz: Poisson's ratio nu must lie in (-1.0, 0.5]"),
    (lambda: hertz(1e4, 1.0, 1.0, G=0.0), "hertz: shear modulus G [Pa] must lie in (0.0, inf]"),
    (lambda: hertz_stiffness(1.0, np.array([1.0, -1.0])), "curvature sum B [1/m] must lie"),
    (lambda: polach(1e4, -0.3, 5e-3, 4e-3, 1e-3, 0.0, 0.0), "polach: friction mu must lie in [0.0"),
    (lambda: polach(1e4, 0.3, 5e-3, 4e-3, 1e-3, 0.0, 0.0, nu=0.7), "polach: Poisson's ratio nu"),
    (lambda: HuntCrossley(0.8).force(1e9, 1e-4, 0.1, impact_velocity=0.0),
     "impact_velocity must lie in (0.0, inf], got 0.0"),
    (lambda: Flores(0.8).force(1e9, 1e-4, 0.1, impact_velocity=np.nan), "impact_velocity"),
]


@pytest.mark.parametrize("call, message", BAD_INPUTS)
def test_bad_physical_inputs_are_named(call, message):
    with pytest.raises(ValueError, match=None) as error:
        call()
    assert message in str(error.value)


def test_traced_inputs_are_not_checked():
    force = jax.jit(lambda mu: polach(1e4, mu, 5e-3, 4e-3, 1e-3, 0.0, 0.0)[0])(0.3)
    assert np.isfinite(float(force)) and float(force) < 0.0
