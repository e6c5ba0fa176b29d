"""The steady curving state: the vehicle's relative equilibrium in a circular curve.

On a track of one circular arc (radius ``R``, constant cant) the loads do not change
when the whole vehicle turns about the vertical axis through the curve's centre ``c``.
A vehicle running at a constant speed ``V`` (on the centreline) then has a steady state
in the frame turning at ``Omega = V / R`` about that axis (positive for a left curve):
every body at rest in it, each wheelset spinning about its axle. It is what GENSYS and
SIMPACK call the quasi-static curving state, and the linear stability in a curve is
taken about it (:mod:`jaxrail.stability.linear`).

Unknowns: each body's pose (dr [m], theta [rad] from the rest pose the vehicle has on
the arc, :func:`jaxrail.vehicles.initial_state`), each wheelset's spin [rad/s] about its
axle, and the tangential force ``F`` [N] on one body (the carbody, else the frame, else
the first wheelset) that holds the speed against the curving resistance, as a traction
or speed controller does. Equations: every body's acceleration in the turning frame is
zero (eq. (19) with the frame's centripetal and gyroscopic terms) and the joints hold.
Newton's method with least-squares steps (the Jacobian by forward-mode
differentiation, its columns scaled): the rotation of the whole vehicle about the
curve's axis and each wheelset's angle about its axle leave the equations unchanged,
and the minimum-norm step leaves them alone. Steps move no pose by more than 1 mm or
1 mrad and are halved while they raise the residual: the start (every body on its own
station of the arc) yaws a bogie's wheelsets radially against stiff primary springs,
and Polach's law, which has no derivative at zero creepage, makes the first linear
models poor. Where Newton's method does not converge from there, the vehicle runs
:data:`SETTLE_S` s round the arc from its rest pose (the time integration, IMEX) and
Newton's method starts again from where it went, turned back about the curve's axis.
Each solve after the first (same parameters and track) starts from the state solved at
the nearest speed, through states :data:`SPEED_STEP` apart where that is further away
(continuation in speed): the settling run cannot serve above the critical speed, where
the vehicle hunts round the arc instead of settling.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..multibody import constraints, initial_element_states, velocities_from_twists
from ..multibody import quaternion as qt
from ..track import to_track_coordinates, track_frame
from ..vehicles.drive import ConstantForce
from ..vehicles.loads import resolve_contact_model, vehicle_accelerations
from .linear import SteadyMotion, is_one_arc, perturbed_pose, steady_motion
from .nonlinear import driven_body

MAX_ITERATIONS = 60
STEP_TOLERANCE = 1e-11  # [m, rad]: Newton stops when a step moves every pose by less
MAX_STEP = 1e-3  # [m, rad]: the largest move of a pose in one step (a trust region)
SPEED_STEP = 5.0  # [m/s]: a state further than this from every one solved is reached in steps
SETTLE_S = 3.0  # [s] simulated from the rest pose when Newton's method does not converge
SINGULAR = 1e-10  # relative singular value below which a direction is left alone
RESIDUAL_TOLERANCE = 1e-6  # [m/s^2, rad/s^2] largest acceleration left at convergence


def curve_frame(track, speed):
    """``(frame_rate (3,), centre (3,))``: the angular velocity [rad/s] of the frame in
    which the steady curving state at ``speed`` [m/s] is at rest, and the curve's centre
    [m] (global), of a track of one arc."""
    kappa = track.curvature_start[0]
    heading = track.heading_start[0]
    centre = jnp.stack([track.x_start[0] - jnp.sin(heading) / kappa,
                        track.y_start[0] + jnp.cos(heading) / kappa, jnp.zeros(())])
    return jnp.stack([jnp.zeros(()), jnp.zeros(()), kappa * speed]), centre


def held_body(vehicle) -> int:
    """The body the tangential force acts on: the speed drive's (the carbody, else the
    frame), else the first wheelset."""
    try:
        return driven_body(vehicle)
    except ValueError:
        return int(vehicle.wheelsets[0])


def check_curving_vehicle(vehicle) -> None:
    """ValueError for a vehicle whose joints to the ground do not turn with the curve:
    only a revolute joint about the vertical does (the suspended wheelset built with
    ``curve_radius``); a prismatic guide holds a straight path."""
    for group in vehicle.system.joint_groups:
        grounded = [name for i, j, name in zip(group.body_i, group.body_j, group.names)
                    if i < 0 or j < 0]
        if grounded and group.kind != "revolute":
            raise ValueError(f"{vehicle.name!r} is held to the ground by the {group.kind} "
                             f"joint(s) {grounded}: it cannot run round a curve (build the "
                             f"suspended wheelset with curve_radius=R for a curve)")


def _state(u, base: SteadyMotion, wheelsets, frame_rate, centre):
    """``(q, velocity (n, 3), angular velocity (n, 3))`` of the unknowns ``u``."""
    n = base.q.shape[0] // 7
    q = perturbed_pose(u[:6 * n].reshape(n, 6), base.q)
    axle = jax.vmap(qt.rotation_matrix)(q.reshape(n, 7)[:, 3:])[:, :, 1]
    spin = jnp.zeros(n).at[wheelsets].set(u[6 * n:6 * n + len(wheelsets)])
    omega = frame_rate + spin[:, None] * axle
    velocity = jnp.cross(frame_rate, q.reshape(n, 7)[:, :3] - centre)
    return q, velocity, omega


def unknowns_of_state(q, qdot, base: SteadyMotion, wheelsets, centre, body):
    """The unknowns (host NumPy, the tangential force zero) of a state ``(q, qdot)``
    anywhere round the arc: turned back about the curve's axis until body ``body`` is
    where it is in ``base``, then measured from ``base``."""
    n = base.q.shape[0] // 7
    bodies, rest = np.asarray(q).reshape(n, 7), np.asarray(base.q).reshape(n, 7)
    centre = np.asarray(centre)
    arm, home = bodies[body, :2] - centre[:2], rest[body, :2] - centre[:2]
    angle = np.arctan2(home[1], home[0]) - np.arctan2(arm[1], arm[0])
    turn_p = qt.from_axis_angle(jnp.array([0.0, 0.0, 1.0]), angle)
    turn = np.asarray(qt.rotation_matrix(turn_p))
    position = centre + (bodies[:, :3] - centre) @ turn.T
    p = np.asarray(jax.vmap(lambda a: qt.multiply(turn_p, a))(jnp.asarray(bodies[:, 3:])))
    conjugate = rest[:, 3:] * np.array([1.0, -1.0, -1.0, -1.0])
    relative = np.asarray(jax.vmap(qt.multiply)(jnp.asarray(p), jnp.asarray(conjugate)))
    theta = 2.0 * np.sign(relative[:, :1]) * relative[:, 1:]  # small rotation vectors
    rates = np.asarray(qdot).reshape(n, 7)[:, 3:]
    omega = 2.0 * np.einsum("bij,bj->bi", np.asarray(jax.vmap(qt.e_matrix)(
        jnp.asarray(bodies[:, 3:]))), rates) @ turn.T
    axle = np.asarray(jax.vmap(qt.rotation_matrix)(jnp.asarray(p)))[:, :, 1]
    spin = np.einsum("wi,wi->w", omega[wheelsets], axle[wheelsets])
    return np.concatenate([np.concatenate([position - rest[:, :3], theta], axis=1).reshape(-1),
                           spin, np.zeros(1)])


def curving_setup(vehicle, params, track, speed, model):
    """``(base, frame_rate, centre, u0)``: the rest pose the unknowns are measured from
    (:class:`~jaxrail.stability.linear.SteadyMotion`), the turning frame
    (:func:`curve_frame`) and the unknowns' start (every body at its rest pose, the
    wheelsets rolling at ``speed`` [m/s], no tangential force)."""
    base = steady_motion(vehicle, params, track, speed, model)
    frame_rate, centre = curve_frame(track, speed)
    n = base.q.shape[0] // 7
    wheelsets = np.asarray(vehicle.wheelsets)
    axle = jax.vmap(qt.rotation_matrix)(base.q.reshape(n, 7)[:, 3:])[:, :, 1]
    spin = jnp.einsum("wi,wi->w", base.angular_velocity[wheelsets], axle[wheelsets])
    u0 = jnp.concatenate([jnp.zeros(6 * n), spin, jnp.zeros(1)])
    return base, frame_rate, centre, u0


def curving_state(u, vehicle, base, frame_rate, centre):
    """``(q, qdot)`` (global) of the unknowns ``u`` (module docstring)."""
    q, velocity, omega = _state(u, base, np.asarray(vehicle.wheelsets), frame_rate, centre)
    return q, velocities_from_twists(q, velocity, omega)


def _tangent(point, frame_rate, centre):
    """Unit horizontal direction [-] of travel at ``point`` round the curve's axis."""
    arm = (point - centre).at[2].set(0.0)
    direction = jnp.cross(jnp.sign(frame_rate[2]) * jnp.array([0.0, 0.0, 1.0]), arm)
    return direction / jnp.linalg.norm(direction)


def curving_residual(u, vehicle, params, track, base, frame_rate, centre, body, model):
    """The turning frame's accelerations (6 n,) [m/s^2, rad/s^2] of every body and the
    joint constraints [m, rad] at the unknowns ``u`` (module docstring)."""
    n = base.q.shape[0] // 7
    q, velocity, omega = _state(u, base, np.asarray(vehicle.wheelsets), frame_rate, centre)
    qdot = velocities_from_twists(q, velocity, omega)
    bodies = q.reshape(n, 7)
    force = ConstantForce(body, u[-1] * _tangent(bodies[body, :3], frame_rate, centre))
    # the elements' internal states at rest at the pose: in the turning frame nothing
    # moves, so a Maxwell damper carries no force and an air spring's reservoir settles
    elements = initial_element_states(vehicle.system, params.system, q)
    qddot = vehicle_accelerations(vehicle, params, track, 0.0, q, qdot, model,
                                  force, elements).reshape(n, 7)
    alpha = 2.0 * jnp.einsum("bij,bj->bi", jax.vmap(qt.e_matrix)(bodies[:, 3:]),
                             qddot[:, 3:])
    linear = qddot[:, :3] - jnp.cross(frame_rate, jnp.cross(frame_rate, bodies[:, :3] - centre))
    angular = alpha - jnp.cross(frame_rate, omega)
    phi = constraints(vehicle.system, params.system, q, qdot)[0][n:]
    return jnp.concatenate([jnp.concatenate([linear, angular], axis=1).reshape(-1), phi])


@dataclasses.dataclass(frozen=True)
class CurvingState:
    """The steady curving state at one speed (host values).

    Fields: steady (:class:`~jaxrail.stability.linear.SteadyMotion`), speed [m/s],
    tangential_force_n [N] (the force that holds the speed: the curving resistance),
    wheelset_lateral_m (W,) [m] (each wheelset's centre in the track frame, + left),
    wheelset_yaw_rad (W,) [rad] (each axle's yaw to the track's radial line, + left),
    iterations, residual (largest acceleration left [m/s^2, rad/s^2]), unknowns (the
    solution ``u``, module docstring).
    """

    steady: SteadyMotion
    speed: float
    tangential_force_n: float
    wheelset_lateral_m: np.ndarray
    wheelset_yaw_rad: np.ndarray
    iterations: int
    residual: float
    unknowns: np.ndarray


def newton_step(jacobian, residual):
    """The minimum-norm least-squares step ``-J^+ r`` with J's columns scaled to unit
    norm and singular values under :data:`SINGULAR` (relative) left out: the rotation
    about the curve's axis and the wheelsets' angles are not moved, and the tangential
    force (its column of order 1 / mass) weighs like a pose."""
    scale = np.linalg.norm(jacobian, axis=0)
    scale = np.where(scale > 0.0, scale, 1.0)
    u, s, vt = np.linalg.svd(jacobian / scale, full_matrices=False)
    keep = s > SINGULAR * s[0]
    return (vt[keep].T @ ((u[:, keep].T @ -residual) / s[keep])) / scale


class SteadyCurving:
    """The steady curving state of ``vehicle`` on ``track`` (one arc), compiled once
    (the speed, the parameters and the track's numbers traced):
    ``SteadyCurving(vehicle, params, track, model)(speed, params=None, track=None)`` ->
    :class:`CurvingState`."""

    def __init__(self, vehicle, params, track, model=None):
        _check_arc(track)
        check_curving_vehicle(vehicle)
        self.vehicle, self.params, self.track = vehicle, params, track
        self.model = model = resolve_contact_model(model)
        body = held_body(vehicle)
        wheelsets = np.asarray(vehicle.wheelsets)

        def setup(params, track, speed):
            return curving_setup(vehicle, params, track, speed, model)

        def residual(u, params, track, setup_values):
            base, frame_rate, centre, _ = setup_values
            return curving_residual(u, vehicle, params, track, base, frame_rate, centre,
                                    body, model)

        def report(u, track, setup_values):
            base, frame_rate, centre, _ = setup_values
            q, velocity, omega = _state(u, base, wheelsets, frame_rate, centre)
            bodies = q.reshape(-1, 7)

            def wheelset(k):
                s, lateral, _ = to_track_coordinates(track, bodies[k, :3])
                axes = track_frame(track, s)
                axle = qt.rotation_matrix(bodies[k, 3:])[:, 1]
                return lateral, jnp.arctan2(-axle @ axes[:, 0], axle @ axes[:, 1])

            lateral, yaw = jax.vmap(wheelset)(jnp.asarray(wheelsets))
            return SteadyMotion(q, velocity, omega, frame_rate, centre), lateral, yaw

        # (params, track, {speed: u}): the states solved for these params and track; the
        # one nearest in speed starts the next solve
        self._solved = None
        self._setup = eqx.filter_jit(setup)
        # the residual and its Jacobian from one program (forward mode carries the
        # value): a second program for the residual alone compiled the model again
        self._linearised = eqx.filter_jit(jax.jacfwd(lambda *a: (residual(*a),) * 2,
                                                     has_aux=True))
        self._report = eqx.filter_jit(report)

    def _newton(self, u, params, track, setup_values):
        """(u, residual, iterations) of Newton's method from ``u`` (module docstring)."""
        n = self.vehicle.system.n_bodies
        norm = lambda r: np.linalg.norm(r) if np.all(np.isfinite(r)) else np.inf  # noqa: E731
        linearised = lambda u: tuple(np.asarray(x) for x in self._linearised(  # noqa: E731
            u, params, track, setup_values))
        jacobian, r = linearised(u)
        for iteration in range(1, MAX_ITERATIONS + 1):
            step = newton_step(jacobian, r)
            moves = np.max(np.abs(step[:6 * n]))
            small = moves < STEP_TOLERANCE
            step = step * min(1.0, MAX_STEP / max(moves, 1e-300))
            # halve a step that makes the residual worse
            for _ in range(12):
                jacobian_trial, r_trial = linearised(u + step)
                if small or norm(r_trial) <= norm(r):
                    break
                step = 0.5 * step
            u, r, jacobian = u + step, r_trial, jacobian_trial
            if small:
                break
        return u, r, iteration

    def _settle(self, speed, params, track, base: SteadyMotion):
        """``(q, qdot)`` after :data:`SETTLE_S` s of running round the arc from the rest
        pose ``base`` at ``speed`` [m/s] (IMEX; the vehicle coasts: the curving resistance
        slows it by a few mm/s)."""
        from ..simulation import SolverOptions, solve

        # the traceable core under jit (not simulate()'s exported, cached programs: the
        # programs traced above may hold host callbacks an export cannot carry), started
        # from the rest pose already solved, with the duration and the speed traced: one
        # program for every speed, and the one a run started from a curving state uses
        qdot = velocities_from_twists(base.q, base.velocity, base.angular_velocity)
        result = eqx.filter_jit(solve)(self.vehicle, params, track,
                                       jnp.asarray(SETTLE_S, jnp.float64),
                                       jnp.asarray(speed, jnp.float64), initial=(base.q, qdot),
                                       options=SolverOptions(integrator="imex"),
                                       contact_model=self.model)
        if result.status != "successful":
            raise ValueError(f"steady curving at {speed:g} m/s: the settling run ended "
                             f"{result.status} at {float(result.simulated_time_s):.2f} s")
        return np.asarray(result.q)[-1], np.asarray(result.qdot)[-1]

    def __call__(self, speed, params=None, track=None, start=None) -> CurvingState:
        """The state at ``speed`` [m/s]. ``start``: a :class:`CurvingState` (of other
        parameters, e.g. the previous step of a design study) whose poses and tangential
        force start Newton's method, instead of the nearest speed's state of these
        parameters or the rest pose."""
        params = self.params if params is None else params
        track = self.track if track is None else track
        _check_arc(track)
        speed = float(speed)
        if not (np.isfinite(speed) and speed > 0.0):
            raise ValueError(f"steady curving: the speed must be > 0 m/s, got {speed}")
        setup_values = self._setup(params, track, jnp.asarray(speed, jnp.float64))
        u = np.asarray(setup_values[3])
        n = self.vehicle.system.n_bodies
        if self._solved is None or self._solved[0] is not params or self._solved[1] is not track:
            self._solved = (params, track, {})
        solved = self._solved[2]
        if start is not None:  # its poses and tangential force, the spins of this speed
            u = np.concatenate([start.unknowns[:6 * n], u[6 * n:-1], start.unknowns[-1:]])
        elif solved:
            nearest = min(solved, key=lambda v: abs(v - speed))
            while abs(speed - nearest) > SPEED_STEP:  # continuation: through the speeds between
                nearest = nearest + np.sign(speed - nearest) * SPEED_STEP
                self(nearest, params, track)
            # the nearest speed's poses and tangential force, the spins of this speed
            start = solved[nearest]
            u = np.concatenate([start[:6 * n], u[6 * n:-1], start[-1:]])
        u, r, iteration = self._newton(u, params, track, setup_values)
        if not np.max(np.abs(r[:6 * n])) < RESIDUAL_TOLERANCE:
            # settle by a simulation from the rest pose, then Newton from where it went
            q, qdot = self._settle(speed, params, track, setup_values[0])
            u = unknowns_of_state(q, qdot, setup_values[0], np.asarray(self.vehicle.wheelsets),
                                  setup_values[2], held_body(self.vehicle))
            u, r, more = self._newton(u, params, track, setup_values)
            iteration += more
        largest = float(np.max(np.abs(r[:6 * n])))
        if not largest < RESIDUAL_TOLERANCE:
            raise ValueError(f"steady curving at {speed:g} m/s: Newton's method left an "
                             f"acceleration of {largest:.3g} after {iteration} iterations "
                             f"(no steady curving state near the centred start: a flange "
                             f"climb, or a curve too tight for the speed?)")
        solved[speed] = u
        steady, lateral, yaw = self._report(u, track, setup_values)
        return CurvingState(steady, speed, float(u[-1]), np.asarray(lateral), np.asarray(yaw),
                            iteration, largest, np.asarray(u))


def _check_arc(track) -> None:
    if not is_one_arc(track):
        raise ValueError(f"the steady curving state needs a track of one arc "
                         f"(Track.from_segments([Arc(...)])), got {list(track.kinds)}")
