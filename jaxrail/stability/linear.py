"""Linear stability of a vehicle's steady motion on straight track and in a circular curve.

The steady motion: every body moves along the track at ``speed``, the wheelsets centred
on the rails at their rest pose (:func:`jaxrail.vehicles.initial_state`) and rolling at
``speed / rolling radius``. It is a relative equilibrium: on an ideal straight track the
loads do not depend on the distance travelled nor on the wheelsets' spin angle (the
wheels are bodies of revolution, their inertia is symmetric about the axle and the
axle's revolute joints turn freely). The perturbation of it therefore obeys linear
equations with constant coefficients, in co-moving coordinates (12 per body, global
axes):

    z = (dr, theta) of each body, then (dv, domega) of each body,

``dr`` [m] the centre's displacement from the steady motion, ``theta`` [rad] the small
rotation (rotation vector, applied on the left: A = exp(theta) A_steady), ``dv`` [m/s]
and ``domega`` [rad/s] the changes of the centre's velocity and of the angular velocity.
Their equations are ``dr' = dv``, ``theta' = domega + omega0 - exp(theta) omega0`` (first
order; omega0 the steady angular velocity, the spin) and ``(dv', domega')`` the
accelerations of eq. (19) with the full contact model, both contact modes. The matrix
``A = dz'/dz`` at z = 0 is taken by forward-mode differentiation of all of it.

In a circular curve (a track of one :class:`~jaxrail.track.Arc`) the steady motion is
the steady curving state (:mod:`jaxrail.stability.curving`): every body at rest in a
frame turning at ``Omega = V / R`` about the vertical through the curve's centre ``c``,
the wheelsets spinning. The same coordinates are then taken in that frame (its axes are
the global ones at t = 0): the velocity is ``v = v0 + Omega x dr + dv`` and the rates
gain the frame's terms, ``dv' = a - 2 Omega x dv - Omega x (Omega x (r - c))`` and
``domega' = alpha - Omega x omega``, with ``omega0 - Omega`` in place of ``omega0`` in
``theta'``. On straight track ``Omega = 0`` and these are the equations above. The
constant tangential force that holds the speed in the curve drops out of A.

A vehicle whose force elements have internal states (a Maxwell damper's piston, an air
spring's orifice: :mod:`jaxrail.multibody.elements_series`) has them after the bodies'
rows, ``z = (dr, theta, dv, domega, dz)``: ``dz`` the change of each internal state from
its steady value, in the order of ``State.elements`` raveled (kinds sorted by name, then
element by element). Their rows are first order, ``dz' = zdot`` of the perturbed state
(:func:`jaxrail.multibody.element_rates`). In the steady motion every element is at rest
at the steady pose (:func:`jaxrail.multibody.initial_element_states`): its length does
not change, on straight track or in the curve's turning frame, so a Maxwell damper
carries no force (its rate ``v(F)`` vanishes only there) and an air spring's reservoir
has settled. A vehicle without such elements has ``z`` of 12 n rows, as before.

The joints tie these coordinates: A leaves the tangent space of the constraint manifold
(the positions' and velocities' linearised constraints) invariant, and the modes of the
vehicle are A's eigenvalues on that space (an orthonormal basis from the constraints'
null space, extended by the identity on the internal states, which no joint ties).
Eigenvalues outside it are Baumgarte's stabilisation, not the vehicle.

A **hunting mode** is an oscillatory mode whose kinetic energy (of the rates of dr and
theta, the wheelsets' spin left out) lies mostly in the wheelsets' lateral and yaw motion (:data:`HUNTING_SHARE`); its frequency is
``Im(lambda) / 2 pi`` and its damping ratio ``-Re(lambda) / |lambda|``.
"""

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from jax.flatten_util import ravel_pytree

from ..multibody import (constraints, element_rates, initial_element_states,
                         join_coordinates, velocities_from_twists)
from ..multibody import forces as fc
from ..multibody import quaternion as qt
from ..multibody.system import stateful_groups
from ..vehicles.initial import initial_state
from ..vehicles.loads import resolve_contact_model, vehicle_accelerations

HUNTING_SHARE = 0.5
"""Least share of a mode's kinetic energy in the running gear's lateral and yaw motion
for it to count as hunting (:func:`running_gear`)."""
MIN_FREQUENCY_HZ = 0.05  # [Hz] below this a mode is not oscillatory (drift, rolling)
NULL_TOLERANCE = 1e-9  # relative singular value below which a constraint row is void


def check_ideal(track) -> None:
    """ValueError unless ``track`` is ideal and rigid (the steady motion is a relative
    equilibrium there only)."""
    if getattr(track, "irregularity", None) is not None:
        raise ValueError("the stability analysis needs the ideal track: this track has "
                         "irregularities (track.with_irregularity(None))")
    if getattr(track, "support", None) is not None:
        raise ValueError("the stability analysis is for rigid rails: this track is flexible "
                         "(track.with_support(None))")


def is_one_arc(track) -> bool:
    """Whether ``track`` is one circular arc (where the steady motion is the steady
    curving state)."""
    return list(track.kinds) == ["arc"]


def check_track(track) -> None:
    """ValueError unless ``track`` is ideal, rigid, and one straight or one circular arc
    (where the steady motion is a relative equilibrium)."""
    check_ideal(track)
    kinds = list(track.kinds)
    if not (all(kind == "straight" for kind in kinds) or is_one_arc(track)):
        raise ValueError(f"the stability analysis is implemented on straight track or on "
                         f"one circular arc (Track.from_segments([Arc(...)])): this track's "
                         f"segments are {kinds}")


def check_straight(track) -> None:
    """ValueError unless ``track`` is ideal, rigid and straight."""
    check_ideal(track)
    if any(kind != "straight" for kind in track.kinds):
        raise ValueError(f"this method is implemented on straight track only: this track's "
                         f"segments are {list(track.kinds)}")


class SteadyMotion(NamedTuple):
    """A steady motion (global axes, t = 0): ``q`` (7 n,) the coordinates, ``velocity``
    (n, 3) [m/s] and ``angular_velocity`` (n, 3) [rad/s] of each body, ``frame_rate``
    (3,) [rad/s] the angular velocity of the frame in which it is at rest (zero on
    straight track) and ``centre`` (3,) [m] a point of that frame's axis."""

    q: jax.Array
    velocity: jax.Array
    angular_velocity: jax.Array
    frame_rate: jax.Array
    centre: jax.Array


def _small_rotation(theta):
    """Unit quaternion of the small rotation vector ``theta`` [rad] (exact to first
    order, smooth at zero)."""
    return qt.normalize(jnp.concatenate([jnp.ones(1), 0.5 * theta]))


def steady_motion(vehicle, params, track, speed, model=None) -> SteadyMotion:
    """The steady motion on straight track (module docstring): the vehicle's rest pose at
    the start of the track, every body moving along it at ``speed`` [m/s]."""
    start = initial_state(vehicle, params, track, speed, 0.0, None, model)
    q0, qdot0 = start.q, start.qdot
    n = q0.shape[0] // 7
    body, rate = q0.reshape(n, 7), qdot0.reshape(n, 7)
    omega0 = 2.0 * jnp.einsum("bij,bj->bi", jax.vmap(qt.e_matrix)(body[:, 3:]), rate[:, 3:])
    zero = jnp.zeros(3, q0.dtype)
    return SteadyMotion(q0, rate[:, :3], omega0, zero, zero)


def perturbed_pose(position, q0):
    """``q`` (7 n,) of the bodies of ``q0`` moved by ``position`` (n, 6): (dr [m], theta
    [rad]) each, the rotation applied on the left."""
    n = q0.shape[0] // 7
    body = q0.reshape(n, 7)
    p = jax.vmap(lambda t, p0: qt.multiply(_small_rotation(t), p0))(position[:, 3:],
                                                                      body[:, 3:])
    return join_coordinates(body[:, :3] + position[:, :3], p)


def element_state_count(system) -> int:
    """Rows of ``z`` after the bodies' 12 n: the internal states of the force elements of
    ``system`` (a :class:`~jaxrail.multibody.System`; 0 without such elements)."""
    return sum(len(g.body_i) * fc.FORCE_KINDS[g.kind].states
               for g in stateful_groups(system))


def state_size(vehicle) -> int:
    """Rows of the co-moving coordinates ``z``: 12 per body and the elements' internal
    states (:func:`element_state_count`)."""
    return 12 * vehicle.system.n_bodies + element_state_count(vehicle.system)


def perturbed_elements(z, system, system_params, steady: SteadyMotion):
    """The force elements' internal states ``{kind: (k, r)}`` of the perturbation ``z``:
    at rest at the steady pose (module docstring) plus ``z``'s rows after the bodies';
    ``{}`` for a system without such elements."""
    rest = initial_element_states(system, system_params, steady.q)
    if not rest:
        return rest
    flat, unravel = ravel_pytree(rest)
    return unravel(flat + z[12 * system.n_bodies:])


def full_state(z, steady: SteadyMotion):
    """``(q, qdot)`` of the co-moving perturbation ``z`` (12 n, or more with internal
    states) of the steady motion."""
    n = steady.q.shape[0] // 7
    position, velocity = z[:6 * n].reshape(n, 6), z[6 * n:12 * n].reshape(n, 6)
    q = perturbed_pose(position, steady.q)
    v = steady.velocity + jnp.cross(steady.frame_rate, position[:, :3]) + velocity[:, :3]
    return q, velocities_from_twists(q, v, steady.angular_velocity + velocity[:, 3:])


def comoving_rates(z, system, system_params, steady: SteadyMotion, accelerate):
    """``z'`` of the perturbation ``z`` of ``steady`` for any multibody system (module
    docstring): ``accelerate(q, qdot, elements)`` gives qddot (7 n,) of eq. (19) with
    the system's loads; the internal states' rows are the elements' rates."""
    n = steady.q.shape[0] // 7
    q, qdot = full_state(z, steady)
    elements = perturbed_elements(z, system, system_params, steady)
    qddot = accelerate(q, qdot, elements).reshape(n, 7)
    p = q.reshape(n, 7)[:, 3:]
    angular = 2.0 * jnp.einsum("bij,bj->bi", jax.vmap(qt.e_matrix)(p), qddot[:, 3:])
    position, velocity = z[:6 * n].reshape(n, 6), z[6 * n:12 * n].reshape(n, 6)
    rate = steady.frame_rate
    spin = steady.angular_velocity - rate  # each body's angular velocity in the frame
    turned = jax.vmap(lambda t, w: qt.matvec(qt.rotation_matrix(_small_rotation(t)), w))(
        position[:, 3:], spin)
    theta_rate = velocity[:, 3:] + spin - turned
    arm = q.reshape(n, 7)[:, :3] - steady.centre
    linear = (qddot[:, :3] - 2.0 * jnp.cross(rate, velocity[:, :3])
              - jnp.cross(rate, jnp.cross(rate, arm)))
    angular = angular - jnp.cross(rate, steady.angular_velocity + velocity[:, 3:])
    rows = [jnp.concatenate([velocity[:, :3], theta_rate], axis=1).reshape(-1),
            jnp.concatenate([linear, angular], axis=1).reshape(-1)]
    if elements:
        rows.append(ravel_pytree(element_rates(system, system_params, q, qdot, elements))[0])
    return jnp.concatenate(rows)


def comoving_rhs(z, vehicle, params, track, steady: SteadyMotion, model):
    """``z'`` (:func:`state_size`,) of the perturbation ``z`` of the steady motion
    ``steady`` of a vehicle on ``track`` with the contact ``model`` (module docstring)."""
    def accelerate(q, qdot, elements):
        return vehicle_accelerations(vehicle, params, track, 0.0, q, qdot, model,
                                     elements=elements)

    return comoving_rates(z, vehicle.system, params.system, steady, accelerate)


def joint_rows(system, system_params, z, steady):
    """Joint constraints Phi and Phidot (normalisation rows left out) at ``z``."""
    q, qdot = full_state(z, steady)
    phi, _, phidot, _ = constraints(system, system_params, q, qdot)
    n = system.n_bodies
    return jnp.concatenate([phi[n:], phidot[n:]])


def linear_system(vehicle, params, track, steady, model=None):
    """``(A, C)``: the state matrix (N, N) of the co-moving perturbation of the steady
    motion ``steady`` (:func:`steady_motion`, or
    :class:`~jaxrail.stability.curving.SteadyCurving`'s) and the linearised joint
    constraints C (2 m, N) (positions, then velocities; zero in the internal states'
    columns); N = :func:`state_size`, 12 n without internal states.
    Traceable: jit, vmap and differentiate it."""
    model = resolve_contact_model(model)
    z0 = jnp.zeros(state_size(vehicle))
    a = jax.jacfwd(comoving_rhs)(z0, vehicle, params, track, steady, model)
    c = jax.jacfwd(joint_rows, argnums=2)(vehicle.system, params.system, z0, steady)
    return a, c


def tangent_basis(c) -> np.ndarray:
    """Orthonormal basis (12 n, k) of the null space of the constraint rows ``c``."""
    c = np.asarray(c, dtype=np.float64)
    size = c.shape[1]
    if c.shape[0] == 0:
        return np.eye(size)
    _, s, vh = np.linalg.svd(c)
    rank = int(np.sum(s > NULL_TOLERANCE * max(s[0], 1.0)))
    return vh[rank:].T


def state_basis(c, n_bodies: int) -> np.ndarray:
    """Orthonormal basis (N, k + e) of the tangent space of ``z`` (N = 12 n + e rows):
    :func:`tangent_basis` of the bodies' columns of ``c``, and the identity on the e
    internal states of the force elements (no joint ties them)."""
    c = np.asarray(c, dtype=np.float64)
    bodies = 12 * n_bodies
    return scipy.linalg.block_diag(tangent_basis(c[:, :bodies]),
                                   np.eye(c.shape[1] - bodies))


@dataclasses.dataclass(frozen=True)
class Modes:
    """The vehicle's modes at one speed (host NumPy).

    Fields:
        eigenvalues: (k,) complex [1/s].
        vectors: (N, k) complex right eigenvectors in the co-moving coordinates
            (N = 12 n and the elements' internal states, :func:`state_size`).
        hunting_share: (k,) share of each mode's kinetic energy in the running gear's
            lateral and yaw motion (:func:`running_gear`).
        frequency_hz: (k,) ``|Im lambda| / 2 pi``.
        damping_ratio: (k,) ``-Re lambda / |lambda|``.
    """

    eigenvalues: np.ndarray
    vectors: np.ndarray
    hunting_share: np.ndarray

    @property
    def frequency_hz(self):
        return np.abs(self.eigenvalues.imag) / (2.0 * np.pi)

    @property
    def damping_ratio(self):
        return -self.eigenvalues.real / np.maximum(np.abs(self.eigenvalues), 1e-300)

    def hunting(self) -> int:
        """Index of the least damped hunting mode (largest real part among the
        oscillatory modes, Im > 2 pi :data:`MIN_FREQUENCY_HZ`, with
        :data:`HUNTING_SHARE`); ValueError if none."""
        candidates = np.flatnonzero((self.eigenvalues.imag > 2 * np.pi * MIN_FREQUENCY_HZ)
                                    & (self.hunting_share >= HUNTING_SHARE))
        if candidates.size == 0:
            raise ValueError("no hunting mode: no oscillatory mode has its kinetic energy "
                             "mostly in the running gear's lateral and yaw motion")
        return int(candidates[np.argmax(self.eigenvalues.real[candidates])])


def running_gear(vehicle) -> tuple[int, ...]:
    """The wheelsets, their axlebox bodies and the frames joined to those by a force
    element (the primary suspension's bogie frames): the bodies that hunt together."""
    unsprung = set(vehicle.wheelsets) | set(vehicle.axleboxes)
    frames = {other for group in vehicle.system.force_groups
              for i, j in zip(group.body_i, group.body_j)
              for body, other in ((i, j), (j, i)) if body in unsprung and other >= 0}
    return tuple(sorted(unsprung | frames))


def kinetic_weights(bodies) -> np.ndarray:
    """Kinetic-energy weights (n, 6) of each body's (dr, theta) rates: its mass [kg]
    thrice, then the diagonal of its inertia [kg m^2] (body axes, which are the track's
    at the steady motion and at rest). ``bodies``: :class:`~jaxrail.multibody.BodyParams`."""
    mass = np.asarray(bodies.mass)
    inertia = np.asarray(bodies.inertia)  # (n, 3, 3)
    return np.concatenate([np.repeat(mass[:, None], 3, axis=1),
                           np.diagonal(inertia, axis1=1, axis2=2)], axis=1)


def _energy_weights(vehicle, params):
    """Kinetic-energy weights (n, 6) of each body's (dr, theta) rates, the wheelsets'
    spin left out (it is cyclic), and the mask (n, 6) of the running gear's lateral and
    yaw motion (:func:`running_gear`)."""
    weights = kinetic_weights(params.system.bodies)
    weights[np.asarray(vehicle.wheelsets), 4] = 0.0
    mask = np.zeros_like(weights, dtype=bool)
    for body in running_gear(vehicle):
        mask[body, 1] = mask[body, 5] = True
    return weights, mask


def modes(vehicle, params, a, c) -> Modes:
    """Eigenvalues and eigenvectors of ``a`` on the null space of ``c``, with each
    mode's hunting share."""
    n = vehicle.system.n_bodies
    basis = state_basis(c, n)
    a = np.asarray(a, dtype=np.float64)
    values, small = np.linalg.eig(basis.T @ a @ basis)
    vectors = basis @ small
    weights, mask = _energy_weights(vehicle, params)
    # the rates of (dr, theta) are lambda times the positions' part: |lambda|^2 cancels
    energy = weights.reshape(-1)[:, None] * np.abs(vectors[:6 * n]) ** 2
    share = np.sum(energy[mask.reshape(-1)], axis=0) / np.maximum(np.sum(energy, axis=0),
                                                                  1e-300)
    return Modes(values, vectors, share)
