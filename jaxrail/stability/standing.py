"""The modes of a vehicle standing on the track, and its wheel loads at rest.

**How the wheelsets are held.** At rest nothing rolls, so there is no creepage and the
creep forces vanish: the rails hold a standing wheelset through the normal forces only
(vertically, and laterally on the contact angles), not longitudinally nor in yaw. A
linearisation about rest with the contact model would leave the wheelsets free to slide
along and to turn on the rails. The modal analysis of a suspension, as VAMPIRE's and
SIMPACK's, clamps the wheelsets instead, and so does this one: each wheelset is fixed to
the ground at its rest pose (a ``fixed`` joint, :class:`~jaxrail.multibody.Fixed`). The
modes are those of the bodies the suspension carries: the carbody, the bogie frames and
the axlebox bodies (which turn about their fixed axles on their revolute joints), with
the force elements' internal states (a Maxwell damper's piston, an air spring's orifice).

The rest pose is the vehicle's static equilibrium on straight, ideal, rigid track at
speed zero (:func:`jaxrail.vehicles.initial_state`), refined by Newton's method on the
clamped system until every body's acceleration vanishes (the preloads of a vehicle
file's load path make it the nominal layout, to rounding). The equations of motion
(eq. (19), all joints, gravity, every force element) are linearised there in the
coordinates of :mod:`jaxrail.stability.linear` (its steady motion being rest), and the
modes are the state matrix's eigenvalues on the joints' tangent space. The force
elements are linearised as they are: a friction damper by its regularisation's slope at
zero velocity, a bump stop in its clearance not at all.

**The wheel loads at rest** are the clamps' reactions at the equilibrium (what the rails
must carry), each wheelset's vertical force and roll moment shared between its wheels
by the lever arms of their contact points (normal-force weighted, from the contact
search at the rest pose). Unlike the rest pose's own loads (each wheel one 2 W-th of the
weight, :mod:`jaxrail.vehicles.initial`) they follow the vehicle's mass distribution.

**Naming a mode.** Its shape's kinetic energy (mass times |dr|^2, inertia times
|theta|^2 per axis, :func:`~jaxrail.stability.linear.kinetic_weights`) is summed per
body; the body with the largest share names it, with every body of at least
:data:`GROUP_SHARE` of that share and the same motion (two bogies bouncing together:
``bogie_1+bogie_2``, ``bounce, in phase``). The motion is the body's axis with the most
energy: longitudinal, lateral, bounce, roll, pitch, yaw (vehicle axes: x forward, y
left, z up); where lateral and roll each hold at least :data:`COUPLED_SHARE` of the
body's energy, the mode is a sway: ``lower sway`` when the body rolls about a point
below its centre of mass (its top swings furthest), ``upper sway`` when about a point
above it (Garg and Dukkipati's lower and upper centre roll, recalled). A mode
whose shape lies in the elements' internal states (relative to the bodies' motion, in
metres and radians, more than :data:`RELAXATION_RATIO` times) is that element's
``relaxation``. Oscillatory modes have ``frequency_hz`` = Im(lambda) / 2 pi (damped) and
``damping_ratio`` = -Re(lambda) / |lambda|, as :class:`~jaxrail.stability.linear.Modes`;
real (overdamped) modes have frequency 0, damping ratio 1 and ``time_constant_s`` =
-1 / lambda.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..multibody import JointParams, accelerations, constraints, initial_element_states
from ..multibody import forces as fc
from ..multibody import joints as jt
from ..multibody import quaternion as qt
from ..multibody.system import Group, System, stateful_groups
from ..track import straight_track
from ..vehicles.initial import initial_state
from ..vehicles.loads import contact_loads
from .curving import newton_step
from .linear import (SteadyMotion, comoving_rates, element_state_count, joint_rows,
                     kinetic_weights, perturbed_pose, state_basis)

MOTIONS = ("longitudinal", "lateral", "bounce", "roll", "pitch", "yaw")
"""The motion of each of a body's six axes (x, y, z, then rotations about them)."""
GROUP_SHARE = 0.5  # a body with this share of the leading body's energy joins its name
COUPLED_SHARE = 0.2  # lateral and roll each at least this share of a body's: a sway
RELAXATION_RATIO = 10.0  # internal states this many times the bodies' motion: relaxation
MAX_ITERATIONS = 20
STEP_TOLERANCE = 1e-12  # [m, rad]: Newton stops when a step moves every pose by less
TRACK_MARGIN = 20.0  # [m] of straight track beyond the vehicle's length at rest


@dataclasses.dataclass(frozen=True)
class StandingMode:
    """One mode of the standing vehicle (module docstring): ``eigenvalue`` [1/s],
    ``frequency_hz`` (0 for a real mode), ``damping_ratio`` [-], ``time_constant_s``
    (-1 / lambda of a real mode, None for an oscillatory one), ``body`` and ``motion``
    (its name), ``energy_share`` [-] (the named bodies' share of its kinetic energy)."""

    eigenvalue: complex
    frequency_hz: float
    damping_ratio: float
    time_constant_s: float | None
    body: str
    motion: str
    energy_share: float


@dataclasses.dataclass(frozen=True)
class VehicleModes:
    """The standing vehicle (host values).

    Fields:
        modes: :class:`StandingMode` tuple, oscillatory ones by frequency, then real
            ones by time constant.
        wheel_loads_n: (W, 2) [N] each wheel's vertical load at rest, leading wheelset
            first, left then right.
        contact_arms_m: (W, 2, 3) [m] each wheel's contact point (normal-force
            weighted) from its wheelset's centre, global, the same order.
        total_mass_kg: every body's mass [kg]; weight_n: its weight [N].
        q: (7 n,) the rest pose (global); residual: the largest acceleration left at
            it [m/s^2, rad/s^2].
    """

    modes: tuple
    wheel_loads_n: np.ndarray
    contact_arms_m: np.ndarray
    total_mass_kg: float
    weight_n: float
    q: np.ndarray
    residual: float


def clamped_system(system: System, system_params, q, bodies):
    """``(System, SystemParams)``: ``system`` with each of ``bodies`` (static indices)
    fixed to the ground at its pose in ``q`` (7 n,), by ``fixed`` joints named
    ``clamp_<body>`` added to the kind's group (kinds in :data:`JOINT_KINDS` order)."""
    index = np.asarray(bodies, dtype=int)
    pose = q.reshape(-1, 7)[index]
    k = len(index)
    clamp = JointParams(point_i=jnp.zeros((k, 3)), point_j=pose[:, :3],
                        frame_i=jnp.tile(jnp.eye(3), (k, 1, 1)),
                        frame_j=jax.vmap(qt.rotation_matrix)(pose[:, 3:]))
    names = tuple(f"clamp_{system.body_names[i]}" for i in index)
    groups = {g.kind: g for g in system.joint_groups}
    joints = dict(system_params.joints)
    old = groups.get("fixed", Group("fixed", (), (), ()))
    groups["fixed"] = Group("fixed", old.body_i + tuple(int(i) for i in index),
                            old.body_j + (jt.GROUND,) * k, old.names + names)
    if "fixed" in joints:
        clamp = jax.tree.map(lambda a, b: jnp.concatenate([a, b]), joints["fixed"], clamp)
    joints["fixed"] = clamp
    ordered = tuple(groups[kind] for kind in jt.JOINT_KINDS if kind in groups)
    clamped = System(system.n_bodies, system.body_names, ordered, system.force_groups)
    return clamped, eqx.tree_at(lambda p: p.joints, system_params, joints)


def clamp_rows(system: System) -> np.ndarray:
    """Indices of the clamps' rows (6 each, in order) among the constraints of a
    :func:`clamped_system`: the last ones of the ``fixed`` group."""
    start = system.n_bodies
    for g in system.joint_groups:
        rows = jt.JOINT_KINDS[g.kind][0] * len(g.body_i)
        if g.kind == "fixed":
            clamps = sum(name.startswith("clamp_") for name in g.names)
            return np.arange(start + rows - 6 * clamps, start + rows)
        start += rows
    return np.arange(0)


def _linearised(system, system_params, q):
    """At rest at ``q`` (7 n,): ``(A, C, rates, phi, reactions)``, the state matrix and
    the joints' rows of the perturbation of rest (:mod:`jaxrail.stability.linear`'s
    coordinates, internal states included), the rates at rest (N,), the joint
    constraints (m,) and the clamps' generalized reactions on every body (n, 7) (the
    joint reactions -Phi_q^T lambda of the clamps' rows): one program."""
    n = system.n_bodies
    zero = jnp.zeros((n, 3))
    steady = SteadyMotion(q, zero, zero, jnp.zeros(3), jnp.zeros(3))
    z0 = jnp.zeros(12 * n + element_state_count(system))

    def accelerate(q, qdot, elements):
        return accelerations(system, system_params, 0.0, q, qdot, None, elements)[0]

    def rates(z):
        value = comoving_rates(z, system, system_params, steady, accelerate)
        return value, value

    a, at_rest = jax.jacfwd(rates, has_aux=True)(z0)
    c = jax.jacfwd(joint_rows, argnums=2)(system, system_params, z0, steady)
    phi = joint_rows(system, system_params, z0, steady)[:c.shape[0] // 2]
    qdot = jnp.zeros_like(q)
    elements = initial_element_states(system, system_params, q)
    lam = accelerations(system, system_params, 0.0, q, qdot, None, elements)[1]
    rows = clamp_rows(system)
    phi_q = constraints(system, system_params, q, qdot)[1]
    reactions = -(lam[rows] @ phi_q[rows]).reshape(n, 7)
    return a, c, at_rest, phi, reactions


_linearised_program = eqx.filter_jit(_linearised)


def rest_linearisation(system, system_params, q):
    """Newton's method (least-squares steps, :func:`~jaxrail.stability.curving.newton_step`)
    from ``q`` to the static equilibrium of ``system`` (a :func:`clamped_system`), and
    :func:`_linearised` there: ``(q, A, C, reactions, residual)``, residual the largest
    acceleration left [m/s^2, rad/s^2]. The Newton steps take the Jacobian from A."""
    n = system.n_bodies
    for _ in range(MAX_ITERATIONS):
        a, c, rates, phi, reactions = (np.asarray(x) for x in _linearised_program(
            system, system_params, q))
        jacobian = np.concatenate([a[6 * n:12 * n, :6 * n], c[:phi.size, :6 * n]])
        step = newton_step(jacobian, np.concatenate([rates[6 * n:12 * n], phi]))
        if np.max(np.abs(step)) < STEP_TOLERANCE:
            break
        q = perturbed_pose(jnp.asarray(step).reshape(n, 6), q)
    return q, a, c, reactions, float(np.max(np.abs(rates[6 * n:12 * n])))


def _rest(vehicle, params, track, model):
    state = initial_state(vehicle, params, track, 0.0, 0.0, None, model)
    _, _, patches, forces = contact_loads(vehicle, params, track, state.q, state.qdot, model)
    weight = jnp.where(patches.active, forces.normal_force, 0.0)  # (W, 2, P)
    point = (jnp.sum(weight[..., None] * patches.rail_point, axis=2)
             / jnp.sum(weight, axis=2)[..., None])
    centres = state.q.reshape(-1, 7)[np.asarray(vehicle.wheelsets), :3]
    return state.q, point - centres[:, None, :]


_rest_program = eqx.filter_jit(_rest)


def rest_pose(vehicle, params, model=None):
    """``(q, arms)``: the vehicle's rest pose (7 n,) on straight track at speed zero
    (:func:`jaxrail.vehicles.initial_state`) and each wheel's contact point relative to
    its wheelset's centre (W, 2, 3) [m], global, normal-force weighted; one program."""
    layout = np.asarray(params.layout)
    track = straight_track(float(np.ptp(layout[:, 0])) + TRACK_MARGIN)
    return _rest_program(vehicle, params, track, model)


def wheel_loads(force, moment, arms) -> np.ndarray:
    """(W, 2) [N] vertical load on each wheel (left, right) of the wheelsets carried by
    ``force`` (W, 3) [N] and ``moment`` (W, 3) [N m] about their centres (global), the
    wheels' contact points at ``arms`` (W, 2, 3) [m] from the centres: the vertical
    forces balance F_z and, with the lateral force at the points' mean height, M_x."""
    loads = []
    for f, m, r in zip(np.asarray(force), np.asarray(moment), np.asarray(arms)):
        height = np.mean(r[:, 2])
        lever = np.array([[1.0, 1.0], [r[0, 1], r[1, 1]]])
        loads.append(np.linalg.solve(lever, [f[2], m[0] + height * f[1]]))
    return np.array(loads)


def vehicle_modes(vehicle, params, model=None) -> VehicleModes:
    """The modes of ``vehicle`` standing on straight track with its wheelsets clamped,
    its wheel loads at rest and its mass (module docstring). ``model``: the contact
    model of the rest pose (default the paper's search)."""
    q0, arms = rest_pose(vehicle, params, model)
    system, system_params = clamped_system(vehicle.system, params.system, q0,
                                           vehicle.wheelsets)
    q, a, c, reactions, residual = rest_linearisation(system, system_params, q0)
    index = np.asarray(vehicle.wheelsets)
    p = np.asarray(q).reshape(-1, 7)[index, 3:]
    # the generalized torque 2 G^T A^T n back to the moment n (G G^T = I)
    moment = np.stack([np.asarray(qt.rotation_matrix(x)) @ (0.5 * np.asarray(qt.g_matrix(x))
                                                             @ g[3:])
                       for x, g in zip(p, reactions[index])]).reshape(-1, 3)
    mass = float(np.sum(np.asarray(params.system.bodies.mass)))
    gravity = float(np.linalg.norm(np.asarray(params.system.gravity)))
    return VehicleModes(name_modes(system, system_params, a, c),
                        wheel_loads(reactions[index, :3], moment, arms), np.asarray(arms),
                        mass, mass * gravity, np.asarray(q), residual)


def name_modes(system, system_params, a, c) -> tuple:
    """The :class:`StandingMode` of each eigenvalue of ``a`` on the tangent space of
    ``c`` (one of each complex pair), named (module docstring)."""
    n = system.n_bodies
    basis = state_basis(c, n)
    values, small = np.linalg.eig(basis.T @ np.asarray(a, dtype=np.float64) @ basis)
    vectors = basis @ small
    weights = kinetic_weights(system_params.bodies)
    labels = _element_labels(system)
    modes = []
    for value, vector in zip(values, vectors.T):
        if value.imag < 0.0:
            continue
        body, motion, share = _name(system, weights, labels, vector)
        if value.imag > 0.0:
            frequency, ratio, tau = value.imag / (2 * np.pi), -value.real / abs(value), None
        else:
            frequency, ratio = 0.0, 1.0 if value.real < 0.0 else -1.0
            tau = float(-1.0 / value.real) if value.real != 0.0 else float("inf")
        modes.append(StandingMode(complex(value), float(frequency), float(ratio), tau,
                                  body, motion, share))
    return tuple(sorted(modes, key=lambda m: (m.frequency_hz == 0.0, m.frequency_hz,
                                              m.time_constant_s or 0.0)))


def _element_labels(system) -> list:
    """The name of each internal state's element (``State.elements`` raveled: kinds by
    name, element by element, then its states)."""
    labels = []
    for g in sorted(stateful_groups(system), key=lambda g: g.kind):
        for i, name in enumerate(g.names):
            labels += [name or f"{g.kind}_{i + 1}"] * fc.FORCE_KINDS[g.kind].states
    return labels


def _name(system, weights, labels, vector):
    """``(body, motion, share)`` of one mode's shape ``vector`` (module docstring)."""
    n = system.n_bodies
    shape = vector[:6 * n].reshape(n, 6)
    internal = vector[12 * n:]
    if internal.size and np.max(np.abs(internal)) > RELAXATION_RATIO * np.max(np.abs(shape)):
        return labels[int(np.argmax(np.abs(internal)))], "relaxation", 1.0
    energy = weights * np.abs(shape) ** 2
    total = max(float(np.sum(energy)), 1e-300)
    per_body = np.sum(energy, axis=1) / total
    lead = int(np.argmax(per_body))
    motion = _motion(energy[lead], shape[lead])
    group = [b for b in np.argsort(-per_body)
             if per_body[b] >= GROUP_SHARE * per_body[lead]
             and _motion(energy[b], shape[b]) == motion]
    body = "+".join(system.body_names[b] for b in sorted(group))
    if len(group) == 2:
        axis = int(np.argmax(energy[lead]))
        ratio = shape[group[1], axis] / shape[group[0], axis]
        motion += ", in phase" if ratio.real > 0.0 else ", anti-phase"
    return body, motion, float(np.sum(per_body[group]))


def _motion(energy, shape) -> str:
    """The motion of one body (module docstring) from its energy (6,) and shape (6,)."""
    share = energy / max(float(np.sum(energy)), 1e-300)
    if share[1] >= COUPLED_SHARE and share[3] >= COUPLED_SHARE:
        # the point at height h above the centre moves sideways by y - roll h
        centre = (shape[1] / shape[3]).real
        return "upper sway" if centre > 0.0 else "lower sway"
    return MOTIONS[int(np.argmax(share))]
