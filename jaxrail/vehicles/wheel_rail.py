"""Wheel-rail forces on a wheelset: the contact search, Hertz, a normal law and Polach.

For each patch of each wheel (:func:`jaxrail.contact.search_wheelset`):

1. Hertz stiffness ``K`` from the principal curvatures at the contact point (wheel
   rolling direction ``curvature_wheel_x``, lateral profile curvatures of wheel and
   rail; the rail is straight along the track), scaled by ``stiffness_scale``.
2. Normal force ``N = law.force(K, delta, delta_dot)``; ``delta_dot`` is the rate at
   which the wheel point moves into the rail along the contact normal.
3. The Hertz ellipse for ``N`` (``a, b`` grow as ``N^(1/3)``), the creepages of the
   wheelset's rigid-body motion at the contact point (midway between the wheel point and
   its foot on the rail), and Polach's creep forces.
4. The force on the wheelset ``N n + fx t + fy l`` at the contact point, and its moment
   about the wheelset centre.

Inactive patch slots give exactly zero force with finite gradients. Everything is in
the global frame and SI units.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._constants import STEEL_POISSON, STEEL_SHEAR_MODULUS
from .._float64 import f64
from ..compilation import computed_once, traced_once
from ..contact.creepage import creepages
from ..contact.hertz import hertz_from_curvatures
from ..contact.normal import Eq17, NormalLaw
from ..contact.polach import PolachParameters, polach
from ..contact.search import SearchConfig, search_wheelset


class ContactParameters(eqx.Module):
    """Physical parameters of the wheel-rail contact (all traced, differentiable).

    Fields:
        friction: friction coefficient mu [-] (mu0 with the Polach 2005 options).
        stiffness_scale: factor on the Hertz stiffness [-] (1 = Hertz).
        shear_modulus: G [Pa]; poisson: nu [-] (wheel and rail of the same steel).
        normal_law: the normal force law (default the paper's eq. 17 with c_e = 0.8,
            v0 = 0.01 m/s, see docs/normal-forces.md for why).
        polach: Polach 2005 options (defaults reduce to Polach 1999).
    """

    friction: Float[Array, ""] = eqx.field(converter=f64, default=0.4)
    stiffness_scale: Float[Array, ""] = eqx.field(converter=f64, default=1.0)
    shear_modulus: Float[Array, ""] = eqx.field(converter=f64, default=STEEL_SHEAR_MODULUS)
    poisson: Float[Array, ""] = eqx.field(converter=f64, default=STEEL_POISSON)
    normal_law: NormalLaw = eqx.field(default_factory=Eq17)
    polach: PolachParameters = eqx.field(default_factory=PolachParameters)


class PatchForces(eqx.Module):
    """Per patch (leading shape ``(2, P)``: left/right wheel, patch slot).

    Fields: normal_force [N]; creep_force_x, creep_force_y [N] along the contact
    frame's longitudinal and lateral axes (on the wheel); creepage_x, creepage_y [-],
    spin [1/m]; semi_axis_a, semi_axis_b [m]; stiffness [N/m^1.5]; force (..., 3) on
    the wheel, global [N].
    """

    normal_force: Array
    creep_force_x: Array
    creep_force_y: Array
    creepage_x: Array
    creepage_y: Array
    spin: Array
    semi_axis_a: Array
    semi_axis_b: Array
    stiffness: Array
    force: Array


# Floor on the Hertz curvature ratio B/A at a wheel-rail patch, a guard. The lateral
# curvature sum is the patch's ``curvature_contact_y``: the gap's secant curvature over
# +-1 mm for narrow patches, the overlap curvature for wide ones, which stays positive
# where the S1002 throat conforms to the UIC60 gauge corner (there the profile curvatures
# with a 1e-3 floor make the stiffness jump 25-fold over 4 mm of profile, enough to
# derail the leading wheelset in the paper's curve). The floor catches narrow
# patches where the gap is concave (small second patches sharing a run on the S1002
# tread, B/A 0.02-0.6); 0.3 lies below the flange root (15) and flange (106-133):
# docs/normal-forces.md.
MIN_CURVATURE_RATIO = 0.3


def _cube_root(x):
    positive = x > 0.0
    return jnp.where(positive, jnp.cbrt(jnp.where(positive, x, 1.0)), 0.0)


def _patch_hertz(params: ContactParameters, patch):
    """Hertz's solution for a unit load at a patch (stiffness scaled by
    ``stiffness_scale``; NaN where the curvatures are not finite)."""
    # A diverged (NaN) state must stop its own run with a status, not raise Hertz's
    # curvature check for a whole batch: NaN curvatures go past the check and come back
    # as a NaN stiffness (finite states never have them, active or not).
    usable = jnp.isfinite(patch.curvature_wheel_x) & jnp.isfinite(patch.curvature_contact_y)
    radius_x = 1.0 / jnp.where(usable, patch.curvature_wheel_x, 1.0)
    unit = hertz_from_curvatures(1.0, radius_x, jnp.where(usable, patch.curvature_contact_y, 0.0),
                                 0.0, G=params.shear_modulus, nu=params.poisson,
                                 min_curvature_ratio=MIN_CURVATURE_RATIO)
    stiffness = jnp.where(usable, params.stiffness_scale * unit.stiffness, jnp.nan)
    return unit, stiffness


def _patch_rates(patch, centre, velocity, angular_velocity, rail_velocity):
    """The velocity-dependent inputs of a patch's force laws: ``(rate, xi, eta, phi,
    speed)``: the penetration rate [m/s] (the wheel point moving into the rail along
    the normal, relative to the rail, which moves at ``rail_velocity`` (3,) [m/s] on a
    flexible track), the creepages at the middle of the overlap and the rolling speed
    [m/s]."""
    wheel_point_velocity = velocity + jnp.cross(angular_velocity, patch.wheel_point - centre)
    rate = -(wheel_point_velocity - rail_velocity) @ patch.normal
    # Creepages at the middle of the overlap: the deformed interface of two bodies of
    # the same steel (the rail point would bias xi by -delta/r, the wheel point by +).
    interface = 0.5 * (patch.wheel_point + patch.rail_point)
    xi, eta, phi = creepages(velocity, angular_velocity, centre, interface, patch.frame,
                             rail_velocity=rail_velocity)
    return rate, xi, eta, phi, jnp.abs(velocity @ patch.frame[:, 0])


def _patch_laws(params: ContactParameters, active, unit, stiffness, penetration, rate, xi,
                eta, phi, speed):
    """``(normal_force, fx, fy, a, b)`` of one patch from its law inputs."""
    normal_force = jnp.where(active, params.normal_law.force(stiffness, penetration, rate), 0.0)
    growth = _cube_root(normal_force)  # Hertz: a, b grow as N^(1/3)
    a, b = unit.a * growth, unit.b * growth
    fx, fy = polach(normal_force, params.friction, a, b, xi, eta, phi, params.shear_modulus,
                    params.poisson, parameters=params.polach, rolling_speed=speed)
    # each read by the force, the moment, the outputs (and the load Jacobian)
    return computed_once(normal_force, fx, fy, a, b)


def _patch_forces(params: ContactParameters, patch, centre, velocity, angular_velocity,
                  rail_velocity):
    """Forces of one patch slot (scalars); ``patch`` is a ContactPatches entry."""
    unit, stiffness = _patch_hertz(params, patch)
    rate, xi, eta, phi, speed = _patch_rates(patch, centre, velocity, angular_velocity,
                                             rail_velocity)
    normal_force, fx, fy, a, b = _patch_laws(params, patch.active, unit, stiffness,
                                             patch.penetration, rate, xi, eta, phi, speed)
    frame = patch.frame
    force = normal_force * frame[:, 2] + fx * frame[:, 0] + fy * frame[:, 1]
    return PatchForces(normal_force, fx, fy, xi, eta, phi, a, b, stiffness, force)


@traced_once
def patch_force_jacobian(params: ContactParameters, patch, centre, velocity,
                         angular_velocity, d_shift, d_turn, d_velocity, d_angular_velocity,
                         rail_velocity, d_rail_shift, d_rail_velocity):
    """d force / d x (3, m): the global force on the wheel at one patch as m
    quantities x of the wheelset change, the patch's points, frame and curvatures
    held.

    ``d_shift``, ``d_turn`` (3, m): derivatives of the wheelset centre's displacement
    [m] and small rotation [rad]; ``d_velocity``, ``d_angular_velocity`` (3, m): of its
    velocity and angular velocity; all global. The penetration follows the wheel
    point's displacement along the normal (the normal stiffness), the penetration rate
    and creepages follow the velocities (the creep damping). The force laws are
    differentiated in their six scalar inputs only (penetration, rate, creepages,
    rolling speed), so the cost does not grow with m.

    The rail under the patch moves at ``rail_velocity`` (3,) [m/s], and
    ``d_rail_shift``, ``d_rail_velocity`` (3, m) are the derivatives of its displacement
    [m] and velocity [m/s] (all zeros for a rigid rail)."""
    unit, stiffness = _patch_hertz(params, patch)
    arm = patch.wheel_point - centre
    moved = d_shift + jnp.cross(d_turn.T, arm).T - d_rail_shift
    d_penetration = -(patch.normal @ moved)
    rates = lambda v, w, r: jnp.stack(_patch_rates(patch, centre, v, w, r))  # noqa: E731
    by_velocity, by_omega, by_rail = jax.jacfwd(rates, argnums=(0, 1, 2))(
        velocity, angular_velocity, rail_velocity)
    d_inputs = jnp.concatenate([d_penetration[None, :],
                                by_velocity @ d_velocity + by_omega @ d_angular_velocity
                                + by_rail @ d_rail_velocity])
    inputs = jnp.concatenate([patch.penetration[None],
                              rates(velocity, angular_velocity, rail_velocity)])
    laws = lambda u: jnp.stack(_patch_laws(params, patch.active, unit, stiffness, *u)[:3])  # noqa: E731
    d_laws = jax.jacfwd(laws)(inputs) @ d_inputs  # (N, fx, fy) by x
    return patch.frame[:, jnp.array([2, 0, 1])] @ d_laws


@traced_once
def patch_loads(params: ContactParameters, patches, position, velocity, angular_velocity,
                rail_velocity=None):
    """Total wheel-rail force and moment on a wheelset from its contact patches.

    Arguments:
        params: :class:`ContactParameters`.
        patches: the wheelset's :class:`jaxrail.contact.ContactPatches`, leading shape
            ``(2, P)`` (left, right wheel; patch slots), from the paper's search or a
            contact table.
        position (3,): wheelset centre, global [m].
        velocity (3,), angular_velocity (3,): of the wheelset, global [m/s, rad/s].
        rail_velocity (2, 3): of the left and right rail under the wheelset, global
            [m/s] (a flexible track); default zero (rigid rails).

    Returns ``(force (3,), moment (3,), patch_forces)``: the resultant force [N] and its
    moment about the wheelset centre [N m], both global, and the per-patch forces.
    """
    rail_velocity = jnp.zeros((2, 3)) if rail_velocity is None else rail_velocity
    one = lambda patch, rail: _patch_forces(params, patch, position, velocity,  # noqa: E731
                                            angular_velocity, rail)
    forces = jax.vmap(jax.vmap(one, in_axes=(0, None)))(patches, rail_velocity)
    arms = patches.rail_point - position
    moment = jnp.sum(jnp.cross(arms, forces.force), axis=(0, 1))
    return jnp.sum(forces.force, axis=(0, 1)), moment, forces


def wheelset_contact_loads(wheel, track, params: ContactParameters,
                           position, rotation, velocity, angular_velocity,
                           config: SearchConfig = SearchConfig(), s_guess=None):
    """Total wheel-rail force and moment on a wheelset, with the paper's search.

    Arguments:
        wheel, track: as :func:`jaxrail.contact.search_wheelset` (the rails are the
            track's).
        params: :class:`ContactParameters`.
        position (3,), rotation (3, 3): wheelset pose (centre and body axes, global).
        velocity (3,), angular_velocity (3,): of the wheelset, global [m/s, rad/s].

    Returns ``(force (3,), moment (3,), patches, patch_forces)``: the resultant force
    [N] and its moment about the wheelset centre [N m], both global, with the contact
    patches and per-patch forces for output.
    """
    patches = search_wheelset(wheel, track, position, rotation, config, s_guess)
    force, moment, forces = patch_loads(params, patches, position, velocity, angular_velocity)
    return force, moment, patches, forces
