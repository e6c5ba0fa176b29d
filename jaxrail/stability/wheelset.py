"""The linear wheelset coefficients the engine's own contact gives, for textbook models
(Klingel's kinematic wavelength, Wickens' suspended wheelset) and for reports.

At the steady motion on straight track (:func:`jaxrail.stability.linear.steady_motion`),
for the leading wheelset, from the contact model and the force laws the simulations
use:

- the rolling radius ``r0`` [m], the half distance ``l0`` [m] between the contact
  points and the wheel load ``W`` [N] of each wheel's most loaded patch (centred,
  mean of both wheels; where a wheel has two patches, as S1002 on UIC60 1:40 does,
  W is that patch's share);
- the conicity ``lambda = d(r_left - r_right)/dy / 2`` [-] at y = 0 of the radii
  weighted by each patch's normal force (the small-amplitude
  limit of the EN 15302 equivalent conicity), with the wheelset held at its rest
  pose for its load at each shift, by forward-mode differentiation through that pose;
- the gravitational stiffness ``k_g = -dF_y/dy`` [N/m] of the normal forces' lateral
  resultant at the same poses (positive: restoring);
- the linear creep coefficients per wheel, the slopes at zero creepage of the creep
  law (Polach with its options, at the patch's load and ellipse): ``f11 = -dF_x/dxi``,
  ``f22 = -dF_y/deta`` [N], ``f23 = -dF_y/dphi`` [N m]; ``F = -f xi`` is the usual sign;
- the same slopes at zero longitudinal and lateral creepage but at the spin creepage
  ``phi0`` [1/m] the centred rolling contact has (``spin_creepage_1_m``, its magnitude;
  ``sin(gamma) / r`` on a coned tread): ``f11_spin_n``, ``f22_spin_n``,
  ``f23_spin_n_m``. Polach's law adds ``phi a`` to the lateral creepage in its
  resultant, so a spinning contact works further along its creep curve and its slopes
  are lower: 0.8 % for f11 on the 1:40 cone here.

Polach's law scales both creep forces by one coefficient C = sqrt((c11 xi)^2 + (c22
eta)^2) / |(xi, eta)|, so its slopes about a steady creepage are those of that
creepage's direction (:func:`polach_slopes_along`), and it has no derivative at zero
creepage: the linear analysis (:mod:`jaxrail.stability.linear`) takes the slopes of the
steady motion's own creepage (docs/stability.md).
"""

import jax
import jax.numpy as jnp

from ..contact.polach import polach
from ..vehicles.initial import wheelset_contact, wheelset_load, wheelset_rest_pose
from ..vehicles.loads import resolve_contact_model
from ..track import track_frame


def polach_slopes_along(coefficients, xi, eta):
    """``(f11, f22)`` [N]: Polach's creep slopes for small creepages about a steady
    creepage along ``(xi, eta)`` (module docstring), from the axis-wise slopes at the
    rolling contact's spin (``f11_spin_n``, ``f22_spin_n`` of
    :func:`wheelset_coefficients`, which give c11 and c22 up to a common factor)."""
    f11, f22 = coefficients["f11_spin_n"], coefficients["f22_spin_n"]
    norm = jnp.hypot(xi, eta)
    return (f11 * jnp.hypot(xi, f22 / f11 * eta) / norm,
            f22 * jnp.hypot(f11 / f22 * xi, eta) / norm)


def _at_shift(vehicle, params, track, s, load, speed, model, lateral):
    """(rolling radius difference left - right [m], lateral resultant of the normal
    forces [N] (track frame, + left), patches, forces) at the rest pose shifted
    ``lateral`` [m]."""
    height, roll, _ = wheelset_rest_pose(vehicle, params, track, s, lateral, load, speed,
                                         model)
    patches, forces = wheelset_contact(vehicle, params, track, s, lateral, height, roll,
                                       speed, model)
    weight = jnp.where(patches.active, forces.normal_force, 0.0)
    radius = jnp.sum(weight * patches.rolling_radius, axis=1) / jnp.sum(weight, axis=1)
    normal = forces.normal_force[..., None] * patches.frame[..., :, 2]  # (2, P, 3)
    lateral_force = jnp.sum(normal, axis=(0, 1)) @ track_frame(track, s)[:, 1]
    return radius[0] - radius[1], lateral_force, patches, forces


def wheelset_coefficients(vehicle, params, track, speed, s=None, model=None) -> dict:
    """The coefficients of the module docstring (dict of float64 scalars) of a wheelset
    centred at arc length ``s`` [m] (default 10 m) carrying the vehicle's weight per
    wheelset, rolling at ``speed`` [m/s]. Traceable (jit it)."""
    model = resolve_contact_model(model)
    s = jnp.asarray(10.0 if s is None else s, jnp.float64)
    load = wheelset_load(vehicle, params)
    shift = lambda y: _at_shift(vehicle, params, track, s, load, speed, model, y)  # noqa: E731
    (dr, fy, patches, forces), (d_dr, d_fy, _, _) = jax.jvp(
        shift, (jnp.asarray(0.0),), (jnp.asarray(1.0),))
    main = jnp.argmax(forces.normal_force, axis=1)  # the loaded patch of each wheel
    pick = lambda x: jnp.take_along_axis(x, main[:, None], axis=1)[:, 0]  # noqa: E731
    n, a, b = pick(forces.normal_force), pick(forces.semi_axis_a), pick(forces.semi_axis_b)
    contact = params.contact

    def creep(xi, eta, phi):
        return jnp.stack(polach(n, contact.friction, a, b, xi, eta, phi,
                                contact.shear_modulus, contact.poisson,
                                parameters=contact.polach, rolling_speed=speed))

    zero, spin = jnp.zeros(2), pick(forces.spin)
    d_xi, d_eta, d_phi = jax.jacfwd(creep, argnums=(0, 1, 2))(zero, zero, zero)
    s_xi, s_eta, s_phi = jax.jacfwd(creep, argnums=(0, 1, 2))(zero, zero, spin)
    diagonal = lambda d: jnp.diagonal(d, axis1=1, axis2=2)  # (force x/y, wheel)  # noqa: E731
    return {
        "wheel_load_n": jnp.mean(n),
        "rolling_radius_m": jnp.mean(pick(patches.rolling_radius)),
        "half_contact_distance_m": 0.5 * jnp.abs(pick(patches.y_track)[0]
                                                 - pick(patches.y_track)[1]),
        "conicity": 0.5 * d_dr,
        "gravitational_stiffness_n_m": -d_fy,
        "f11_n": -jnp.mean(diagonal(d_xi)[0]),
        "f22_n": -jnp.mean(diagonal(d_eta)[1]),
        "f23_n_m": -jnp.mean(diagonal(d_phi)[1]),
        "spin_creepage_1_m": jnp.mean(jnp.abs(spin)),
        "f11_spin_n": -jnp.mean(diagonal(s_xi)[0]),
        "f22_spin_n": -jnp.mean(diagonal(s_eta)[1]),
        "f23_spin_n_m": -jnp.mean(diagonal(s_phi)[1]),
        "radius_difference_m": dr,
        "normal_lateral_force_n": fy,
    }
