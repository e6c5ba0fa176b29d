"""Reverse-mode gradients through a whole trailer simulation (initial equilibrium,
contact search, forces, diffrax with recursive checkpointing).

CI runs 0.2 s (the compilation of the gradient dominates the cost); the 1 s run and
the comparison with central differences at tight tolerances are in
experiments/trailer_gradient/run.py and docs/simulation.md."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxrail.simulate import SolverOptions, solve
from jaxrail.track import straight_track
from jaxrail.vehicles import trailer


def test_gradient_wrt_stiffness_scale_and_friction_is_finite():
    vehicle, params = trailer()
    track = straight_track(60.0)
    options = SolverOptions(rtol=1e-3, atol=1e-6, n_outputs=2)

    def final_lateral_mm(x):
        p = eqx.tree_at(lambda p: (p.contact.stiffness_scale, p.contact.friction), params,
                        (x[0], x[1]))
        result = solve(vehicle, track, p, 0.2, 18.3, 2e-3, options=options)
        return 1e3 * jnp.sum(result.wheelset_lateral[-1]), result.result

    (value, code), grad = jax.jit(jax.value_and_grad(final_lateral_mm, has_aux=True))(
        jnp.array([1.0, 0.4]))
    assert int(code) == 0  # successful
    assert np.isfinite(float(value)) and np.all(np.isfinite(np.asarray(grad)))
    assert np.all(np.asarray(grad) != 0.0)
