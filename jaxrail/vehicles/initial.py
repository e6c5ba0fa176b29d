"""Initial conditions: a vehicle at rest on its wheels, rolling at a given speed.

Static equilibrium: the suspension bushings carry the static loads as preloads at the
nominal layout (:mod:`jaxrail.vehicles.trailer`), so the sprung bodies are in
equilibrium where the layout puts them. Each wheelset is lowered into the rails and
rolled until each of its wheels carries half of the wheelset's share of the vehicle's
weight (the vehicle is assumed symmetric: weight / number of wheelsets). Axlebox
bodies take their wheelset's height and roll; the other bodies follow the wheelsets'
mean height. A lateral misalignment shifts the whole vehicle sideways. On an irregular
track every body also follows the track's alignment at its own arc length (the
wheelsets find their height, roll and loads on the displaced rails through the contact
model, :mod:`jaxrail.track.rails`).
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np

from ..contact.pose import wheelset_pose
from ..multibody import consistent_initial_conditions, join_coordinates
from ..multibody import initial_state as system_initial_state
from ..multibody import quaternion as qt
from ..multibody import velocities_from_twists
from ..track import track_frame, track_irregularity
from .vehicle import Vehicle, VehicleParams
from .loads import rail_loads, wheelset_loads

HEIGHT_BISECTIONS = 50  # from [r0/2, 3 r0/2]: 4e-16 m
ROLL_BISECTIONS = 40  # from [-MAX_ROLL, MAX_ROLL]: 4e-14 rad
MAX_ROLL = 0.02  # [rad]
STEP = 1e-8  # central-difference step in height [m] and roll [rad] of the Newton step


def wheelset_contact(vehicle, params, track, s, lateral, height, roll, speed, model,
                     deflection=None):
    """``(patches, patch_forces)`` of a wheelset at ``s`` [m], shifted ``lateral`` [m],
    its centre ``height`` [m] above the track plane, rolled by ``roll`` [rad], moving at
    ``speed`` [m/s] and spinning at speed / nominal radius (the spin creepage of the
    coned contact gives lateral creep forces with a vertical component), on rails
    deflected by ``deflection`` (2, 2) [m] at rest (None: rigid rails)."""
    position, rotation = wheelset_pose(track, s, lateral, height, roll)
    velocity = speed * rotation[:, 0]
    spin = (speed / params.nominal_radius) * rotation[:, 1]
    rails = None if deflection is None else (deflection, None)
    _, _, patches, forces = wheelset_loads(vehicle, params, track, position, rotation,
                                           velocity, spin, model, rails)
    return patches, forces


def _wheel_loads(vehicle, params, track, s, lateral, height, roll, speed, model,
                 deflection=None):
    """Upward wheel-rail forces [N] (2,) (left, right wheel; track normal) on the
    wheelset of :func:`wheelset_contact`, and the mid-overlap rolling radius [m]
    weighted by normal force."""
    patches, forces = wheelset_contact(vehicle, params, track, s, lateral, height, roll,
                                       speed, model, deflection)
    up = track_frame(track, s)[:, 2]
    loads = jnp.sum(forces.force @ up, axis=1)
    weight = jnp.where(patches.active, forces.normal_force, 0.0)
    radius = jnp.sum(weight * (patches.rolling_radius - 0.5 * patches.penetration))
    return loads, radius / jnp.sum(weight)


def wheelset_rest_pose(vehicle: Vehicle, params: VehicleParams, track, s, lateral, load,
                       speed=0.0, model=None, deflection=None):
    """Centre height [m] above the track plane and roll [rad] at which each wheel of a
    wheelset at arc length ``s`` [m], shifted ``lateral`` [m] and rolling at ``speed``
    [m/s], carries ``load / 2`` [N]; and the rolling radius [m] there (to the middle
    of the overlap, weighted by normal force). ``model``: the contact model
    (:mod:`jaxrail.vehicles.loads`, default the paper's search). ``deflection``: on a
    flexible track, the rails' deflections (2, 2) [m] under the wheelset (left, right;
    lateral, vertical); None: rigid rails.

    Nested bisections: on the roll (within 20 mrad) for equal wheel loads, each with a
    bisection on the height for the total load; then one Newton step on (height, roll)
    with a central-difference Jacobian. The derivatives with respect to every input
    (the parameters, the track with its irregularity, the place, the shift, the speed,
    the load) are the implicit function theorem's, with the exact Jacobian of the wheel
    loads (forward mode through the contact model, compiled only when differentiated).
    """
    f64 = lambda x: jnp.asarray(x, dtype=jnp.float64)  # noqa: E731
    return _rest_pose(vehicle, (params, track, f64(s), f64(lateral), f64(speed), f64(load),
                                model, deflection))


def _residual(vehicle, inputs, pose):
    """Each wheel's load less half the wheelset's (2,) [N] and the rolling radius [m]
    with the wheelset at ``pose`` (height [m], roll [rad])."""
    params, track, s, lateral, speed, load, model, deflection = inputs
    forces, radius = _wheel_loads(vehicle, params, track, s, lateral, pose[0], pose[1], speed,
                                  model, deflection)
    return forces - 0.5 * load, radius


PROBES = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
# evaluations per roll: HEIGHT_BISECTIONS for the height, one for the wheels' balance
PER_ROLL = HEIGHT_BISECTIONS + 1


@functools.partial(jax.custom_jvp, nondiff_argnums=(0,))
def _rest_pose(vehicle, inputs):
    """(height, roll, radius) of :func:`wheelset_rest_pose` for ``inputs`` = (params,
    track, s, lateral, speed, load, model, deflection).

    The nested bisections and the Newton step's probes run as one loop with one
    evaluation of the wheel loads per pass, so that the contact model is compiled once
    (nested loops and a vmap compiled it three times): passes ``k`` of each block of
    ``PER_ROLL`` bisect the height at the block's roll, the last one weighs the wheels
    at that height and halves the roll's interval; the last five passes are the
    probes."""
    load = inputs[5]
    r0 = inputs[0].nominal_radius
    height_bounds = jnp.stack([0.5 * r0, 1.5 * r0])
    rolls = ROLL_BISECTIONS * PER_ROLL

    def step(i, state):
        roll_bounds, heights, pose, residuals, radii = state
        k = i % PER_ROLL
        probing = i >= rolls
        weighing = (k == PER_ROLL - 1) & ~probing
        roll = 0.5 * (roll_bounds[0] + roll_bounds[1])
        height = 0.5 * (heights[0] + heights[1])
        probe = jnp.asarray(PROBES)[jnp.clip(i - rolls, 0, len(PROBES) - 1)]
        at = jnp.where(probing, pose + STEP * probe, jnp.stack([height, roll]))
        residual, radius = _residual(vehicle, inputs, at)
        left, right = residual + 0.5 * load
        heavy = left + right > load  # too deep: raise
        split = jnp.where(heavy, jnp.stack([height, heights[1]]), jnp.stack([heights[0], height]))
        more_left = left > right  # positive roll lifts the left wheel
        halved = jnp.where(more_left, jnp.stack([roll, roll_bounds[1]]),
                           jnp.stack([roll_bounds[0], roll]))
        slot = jnp.arange(len(PROBES)) == i - rolls
        return (jnp.where(weighing, halved, roll_bounds),
                jnp.where(weighing, height_bounds, jnp.where(probing, heights, split)),
                jnp.where(weighing, at, pose),
                jnp.where(slot[:, None], residual, residuals),
                jnp.where(slot, radius, radii))

    zero = jnp.zeros(())
    start = (jnp.stack([zero - MAX_ROLL, zero + MAX_ROLL]), height_bounds, jnp.zeros(2),
             jnp.zeros((len(PROBES), 2)), jnp.zeros(len(PROBES)))
    *_, pose, residual, radius = jax.lax.fori_loop(0, rolls + len(PROBES), step, start)
    central = lambda x: jnp.stack([x[1] - x[3], x[2] - x[4]], axis=-1) / (2.0 * STEP)  # noqa: E731
    newton = -jnp.linalg.solve(central(residual), residual[0])
    return pose[0] + newton[0], pose[1] + newton[1], radius[0] + central(radius) @ newton


@_rest_pose.defjvp
def _rest_pose_jvp(vehicle, primals, tangents):
    """The implicit function theorem at the rest pose: d pose = -J^-1 (d residual / d
    inputs), J the exact Jacobian of the residual in the pose (forward mode)."""
    (inputs,), (d_inputs,) = primals, tangents
    height, roll, radius = _rest_pose(vehicle, inputs)
    pose = jnp.stack([height, roll])
    # one linearisation for both derivatives (the contact model compiled once for them)
    _, linear = jax.linearize(lambda x, p: _residual(vehicle, x, p), inputs, pose)
    d_residual, d_radius = linear(d_inputs, jnp.zeros(2))
    no_inputs = jax.tree.map(_zero_tangent, d_inputs)
    by_pose, radius_by_pose = jax.vmap(lambda e: linear(no_inputs, e), out_axes=-1)(
        jnp.eye(2))
    d_pose = -jnp.linalg.solve(by_pose, d_residual)
    return (height, roll, radius), (d_pose[0], d_pose[1], d_radius + radius_by_pose @ d_pose)


def _zero_tangent(tangent):
    """A zero of ``tangent``'s type (float0 stays float0: its leaf is not differentiable)."""
    if tangent.dtype == jax.dtypes.float0:
        return tangent
    return jnp.zeros_like(tangent)


def wheelset_load(vehicle: Vehicle, params: VehicleParams):
    """The vehicle's weight per wheelset [N]: what each wheelset carries at rest."""
    weight = -jnp.sum(params.system.bodies.mass) * params.system.gravity[2]
    return weight / vehicle.n_wheelsets


def initial_state(vehicle: Vehicle, params: VehicleParams, track, speed, misalignment=0.0,
                  s0=None, model=None):
    """The :class:`~jaxrail.multibody.State` of the vehicle at rest on the track, rolling
    at ``speed`` [m/s] (on a flexible track with its rails at rest under the wheels; the
    force elements' internal states at rest).

    Arguments:
        s0: arc length [m] of the vehicle's reference point (default: the rearmost
            wheelset 5 m after the start of the track).
        misalignment: lateral shift [m] of the whole vehicle, positive left.
        model: the contact model (:mod:`jaxrail.vehicles.loads`, default the paper's
            search).

    All bodies move along the track at ``speed``; the wheelsets spin at ``speed /
    rolling radius``. The state is projected onto the joint constraints.
    """
    layout = params.layout
    if s0 is None:
        s0 = 5.0 - jnp.min(layout[:, 0])
    speed = jnp.asarray(speed, dtype=jnp.float64)
    misalignment = jnp.asarray(misalignment, dtype=jnp.float64)
    wheelsets = np.asarray(vehicle.wheelsets)
    load = wheelset_load(vehicle, params)
    alignment = lambda s: track_irregularity(track, s)[0]  # noqa: E731
    stations = s0 + layout[wheelsets, 0]
    shift = lambda s: misalignment + alignment(s)  # noqa: E731
    rails = None
    if track.support is None:
        heights, rolls, radii = jax.vmap(lambda s: wheelset_rest_pose(
            vehicle, params, track, s, shift(s), load, speed, model))(stations)
    else:
        heights, rolls, radii, rails = _rest_on_flexible_rails(vehicle, params, track,
                                                               stations, shift, load, speed,
                                                               model)
    lift = jnp.mean(heights) - params.nominal_radius

    # per body: its own wheelset (wheelsets and axleboxes), or -1
    carrier = np.full(len(layout), -1)
    carrier[wheelsets] = np.arange(len(wheelsets))
    carrier[np.asarray(vehicle.axleboxes, dtype=int)] = np.arange(len(vehicle.axleboxes))
    carried = carrier >= 0
    height = jnp.where(carried, heights[carrier], layout[:, 2] + lift)
    roll = jnp.where(carried, rolls[carrier], 0.0)

    def place(x, y, vertical, roll):
        s = s0 + x
        position, rotation = wheelset_pose(track, s, y + misalignment + alignment(s), vertical,
                                           roll)
        return position, qt.from_rotation_matrix(rotation), speed * track_frame(track, s)[:, 0]

    position, p, velocity = jax.vmap(place)(layout[:, 0], layout[:, 1], height, roll)
    q = join_coordinates(position, p)
    spin = jnp.zeros(len(layout)).at[wheelsets].set(speed / radii)
    axle = jax.vmap(qt.rotation_matrix)(p)[:, :, 1]
    qdot = velocities_from_twists(q, velocity, spin[:, None] * axle)
    q, qdot = consistent_initial_conditions(vehicle.system, params.system, q, qdot)
    return system_initial_state(vehicle.system, params.system, q, qdot, rails)


REST_PASSES = 2
"""Rest poses solved on a flexible track: the first on rails lowered by the wheel
loads, the second on rails also moved sideways by the first pose's lateral forces."""


def _rest_on_flexible_rails(vehicle, params, track, stations, shift, load, speed, model):
    """Rest poses (heights, rolls, radii (W,)) of the wheelsets at ``stations`` [m],
    shifted ``shift(s)`` [m], on rails deflected by their wheels' static forces, and the
    rails' rest state ``(w, zeros)`` (W, 2, 2) [m, m/s] (:mod:`jaxrail.track.flexible`).
    The vertical deflection is exact (each wheel carries ``load / 2`` [N] by
    construction); the lateral one is that of the previous pass's forces
    (:data:`REST_PASSES`)."""
    support = track.support
    pressed = jnp.zeros((2, 2)).at[:, 1].set(-0.5 * load)  # each wheel's load on its rail

    def one(s):
        w = support.static_deflection(pressed)  # (2 rails, 2 directions)
        for _ in range(REST_PASSES - 1):
            height, roll, _ = wheelset_rest_pose(vehicle, params, track, s, shift(s), load,
                                                 speed, model, w)
            patches, forces = wheelset_contact(vehicle, params, track, s, shift(s), height,
                                               roll, speed, model, w)
            w = w.at[:, 0].set(support.static_deflection(rail_loads(track, patches,
                                                                    forces))[:, 0])
        height, roll, radius = wheelset_rest_pose(vehicle, params, track, s, shift(s), load,
                                                  speed, model, w)
        return height, roll, radius, w

    heights, rolls, radii, w = jax.vmap(one)(stations)
    return heights, rolls, radii, (w, jnp.zeros_like(w))
