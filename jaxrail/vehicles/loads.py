"""The loads on a vehicle's bodies: the one place where the right-hand side is assembled.

Every user of the equations of motion (:mod:`jaxrail.simulation`, the static
equilibrium, identification, Monte Carlo, the benchmarks) goes through
:class:`VehicleLoads` and :func:`vehicle_accelerations`, so the right-hand side is
written once:

1. the wheelsets' poses and velocities from the state ``(q, qdot)``;
2. the contact patches of each wheelset from a **contact model**
   (:class:`OnlineContact`: the paper's search at every evaluation, the reference;
   :class:`TableContact`: the same search tabulated over the wheel's pose relative to
   its rail, :mod:`jaxrail.contact.table`);
3. per patch Hertz, the normal law and Polach (:func:`jaxrail.vehicles.wheel_rail.patch_loads`);
4. the resultant force and moment on each wheelset, as loads on the bodies ``(n, 3)``
   for eq. (19) (:func:`jaxrail.multibody.accelerations`).

Loads are returned for every body of the system, so further sources (rail masses
under the wheelsets, irregularities through the track) add their terms here.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._constants import CONTACT_MODELS as CONTACT_MODELS
from ..contact.search import search_wheelset
from ..contact.table import ContactTable, table_patches
from ..contact.table_cache import contact_table
from ..multibody import AbstractLoads, accelerations, computed_when
from ..multibody import quaternion as qt
from ..multibody.forces import body_torque
from ..track import track_frame
from .vehicle import Vehicle, VehicleParams, wheelset_states
from .wheel_rail import ContactParameters, patch_force_jacobian, patch_loads


class OnlineContact(eqx.Module):
    """The paper's contact search (:func:`jaxrail.contact.search_wheelset`) at every
    evaluation, with the vehicle's :class:`~jaxrail.contact.SearchConfig`."""

    name = "online"

    def wheelset_patches(self, vehicle: Vehicle, params: VehicleParams, track, position,
                         rotation, deflection=None):
        """Contact patches ``(2, P)`` of the wheelset at ``position`` (3,) [m] with
        body axes ``rotation`` (3, 3), global; ``deflection``: on a flexible track, the
        rails' deflections (2, 2) [m] under it (left, right; lateral, vertical)."""
        return search_wheelset(params.wheel, track, position, rotation, vehicle.config,
                               deflection=deflection)


class TableContact(eqx.Module):
    """Contact patches interpolated from a :class:`~jaxrail.contact.table.ContactTable`
    of the vehicle's wheel on the track's rails (:func:`contact_model` builds or loads it).

    The table is data: it is traced, so a new table of the same grid does not
    recompile."""

    table: ContactTable
    name = "table"

    def wheelset_patches(self, vehicle: Vehicle, params: VehicleParams, track, position,
                         rotation, deflection=None):
        """Contact patches ``(2, P)`` of the wheelset at ``position`` (3,) [m] with body
        axes ``rotation`` (3, 3), global, from the table; ``deflection``: as
        :meth:`OnlineContact.wheelset_patches`."""
        sides = jnp.array([1.0, -1.0])
        return jax.vmap(lambda side, d: table_patches(
            self.table, params.wheel, track, position, rotation, side, d),
            in_axes=(0, None if deflection is None else 0))(
                sides, deflection)


def contact_model(name: str, vehicle: Vehicle, params: VehicleParams, track,
                  progress: bool = False, cache: bool = True):
    """The contact model called ``name`` (:data:`CONTACT_MODELS`) for the vehicle on
    ``track``: the paper's search, or the table of its wheel on the track's rails (from
    the cache, or built and cached with a progress bar when ``progress``; with ``cache``
    False built in memory, neither read from nor written to the cache)."""
    if name == "online":
        return OnlineContact()
    if name == "table":
        table, _ = contact_table(params.wheel, track.rails, vehicle.config, progress=progress,
                                 cache=cache)
        return TableContact(table)
    raise ValueError(f"contact model must be one of {CONTACT_MODELS}, got {name!r}")


def resolve_contact_model(model):
    """``model``, or :class:`OnlineContact` (the paper's search) for ``None``."""
    return OnlineContact() if model is None else model


def rail_axes(track, patches) -> jax.Array:
    """(2, 2, 3): for each rail under a wheelset (left, right), the unit vectors along
    which it deflects (lateral: the canted track frame's ``n``; vertical: its ``b``),
    global, at the rail section under the wheel (``patches`` (2, P) of the wheelset)."""
    frames = jax.vmap(lambda s: track_frame(track, s))(patches.s_rail[:, 0])  # (2, 3, 3)
    return jnp.swapaxes(frames[:, :, 1:], 1, 2)


def rail_loads(track, patches, patch_forces) -> jax.Array:
    """(2, 2) [N]: the wheels' forces on the rails under one wheelset (left, right;
    lateral, vertical; along :func:`rail_axes`), the opposite of the rails' forces on
    the wheels."""
    on_wheels = jnp.sum(patch_forces.force, axis=1)  # (2, 3)
    return -jnp.einsum("sdi,si->sd", rail_axes(track, patches), on_wheels)


def wheelset_loads(vehicle: Vehicle, params: VehicleParams, track, position, rotation,
                   velocity, angular_velocity, model=None, rails=None):
    """Wheel-rail force (3,) [N] and moment (3,) [N m] about the centre of one wheelset,
    global, with its patches and patch forces: ``(force, moment, patches, forces)``.
    ``model``: the contact model (default :class:`OnlineContact`). ``rails``: on a
    flexible track, the deflection and rate ``(w, wdot)`` (2, 2) [m, m/s] of the rails
    under this wheelset (:mod:`jaxrail.track.flexible`; ``wdot`` None: rails at rest,
    no rail velocity in the creepages); None: rigid rails."""
    rail_velocity = None
    deflection = None if rails is None else rails[0]
    patches = resolve_contact_model(model).wheelset_patches(vehicle, params, track, position,
                                                             rotation, deflection)
    if rails is not None and rails[1] is not None:
        rail_velocity = jnp.einsum("sd,sdi->si", rails[1], rail_axes(track, patches))
    force, moment, forces = patch_loads(params.contact, patches, position, velocity,
                                        angular_velocity, rail_velocity)
    return force, moment, patches, forces


def contact_loads(vehicle: Vehicle, params: VehicleParams, track, q, qdot, model=None,
                  rails=None):
    """Wheel-rail loads on all bodies and the contact details.

    Returns ``(forces (n, 3) [N], torques (n, 3) [N m], patches, patch_forces)``: the
    forces at the body centres and the torques, global (zero on bodies that are not
    wheelsets), and per wheelset (leading axis W) the contact patches and their forces.
    ``model``: the contact model (default :class:`OnlineContact`). ``rails``: on a
    flexible track, the rails' deflections and rates ``(w, wdot)``, each (W, 2, 2)
    (:mod:`jaxrail.track.flexible`); None: rigid rails.
    """
    position, rotation, velocity, omega = wheelset_states(vehicle, q, qdot)
    load = lambda r, a, v, w, x: wheelset_loads(vehicle, params, track, r, a, v, w,  # noqa: E731
                                                model, x)
    force, moment, patches, patch_forces = jax.vmap(load)(position, rotation, velocity, omega,
                                                          rails)
    n = vehicle.system.n_bodies
    index = np.asarray(vehicle.wheelsets)
    forces = jnp.zeros((n, 3)).at[index].set(force)
    torques = jnp.zeros((n, 3)).at[index].set(moment)
    return forces, torques, patches, patch_forces


def wheelset_load_jacobian(contact: ContactParameters, patches, q_body, qdot_body, moment,
                           rails=None, axes=None):
    """d g / d (q, qdot) (7, 14): the derivative of a wheelset's generalized wheel-rail
    load g (7,) (force, then the Euler-parameter components of the moment) with
    respect to its own coordinates q_body (7,) and velocities qdot_body (7,), the
    patches held where they are (:func:`jaxrail.vehicles.wheel_rail.patch_force_jacobian`).
    ``moment`` (3,) [N m]: the wheel-rail moment about the centre at this state.

    On a flexible track (``rails`` = the rails' ``(w, wdot)`` (2, 2) under this
    wheelset, ``axes`` (2, 2, 3) their directions, :func:`rail_axes`) the columns are
    (q (7), w (4), qdot (7), wdot (4)) and a second block follows: the wheels' forces
    on the rails (4,) [N] (:func:`rail_loads`, raveled (side, direction)) by the same
    22 columns: ``(d_g (7, 22), d_rail (4, 22))``.

    These are the stiff parts of the contact loads (:mod:`jaxrail.multibody.imex`):
    the normal stiffness and the creep damping; the geometric terms left out are slow."""
    r, p, pdot = q_body[:3], q_body[3:], qdot_body[3:]
    extra = 0 if rails is None else 4
    e = qt.e_matrix(p)
    omega_of_p = jax.jacfwd(lambda x: 2.0 * qt.e_matrix(x) @ pdot)(p)  # (3, 4)
    eye, z3, z4, zx = jnp.eye(3), jnp.zeros((3, 3)), jnp.zeros((3, 4)), jnp.zeros((3, extra))
    # the wheelset's motion per unit change of (r, p, [w], rdot, pdot, [wdot])
    d_shift = jnp.concatenate([eye, z4, zx, z3, z4, zx], axis=1)
    d_turn = jnp.concatenate([z3, 2.0 * e, zx, z3, z4, zx], axis=1)
    d_velocity = jnp.concatenate([z3, z4, zx, eye, z4, zx], axis=1)
    d_omega = jnp.concatenate([z3, omega_of_p, zx, z3, 2.0 * e, zx], axis=1)
    velocity, omega = qdot_body[:3], 2.0 * e @ pdot
    if rails is None:  # rigid rails: they neither move nor depend on anything
        rail_velocity = jnp.zeros((2, 3))
        d_rail_shift = d_rail_velocity = jnp.zeros((2, 3, 14))
    else:
        # rail (side, direction) k moves along axes[side, direction]: columns 7 + k, 18 + k
        unit = jnp.eye(4).reshape(2, 2, 4)
        shifts = jnp.einsum("sdi,sdk->sik", axes, unit)  # (2, 3, 4) per side
        zero = jnp.zeros((2, 3, 7))
        d_rail_shift = jnp.concatenate([zero, shifts, zero, 0.0 * shifts], axis=2)
        d_rail_velocity = jnp.concatenate([zero, 0.0 * shifts, zero, shifts], axis=2)
        rail_velocity = jnp.einsum("sd,sdi->si", rails[1], axes)

    def side(patch_row, v_rail, d_shift_rail, d_velocity_rail):
        one = lambda patch: patch_force_jacobian(  # noqa: E731
            contact, patch, r, velocity, omega, d_shift, d_turn, d_velocity, d_omega,
            v_rail, d_shift_rail, d_velocity_rail)
        return jax.vmap(one)(patch_row)
    d_forces = jax.vmap(side)(patches, rail_velocity, d_rail_shift, d_rail_velocity)
    arms = patches.rail_point - r
    d_moment = jnp.sum(jnp.cross(arms[..., :, None], d_forces, axisa=-2, axisb=-2, axisc=-2),
                       axis=(0, 1))
    torque = lambda x, n: body_torque(x, n)[3:]  # noqa: E731
    by_moment, by_p = jax.jacfwd(torque, argnums=(1, 0))(p, moment)
    d_generalized = by_moment @ d_moment + jnp.concatenate(
        [jnp.zeros((4, 3)), by_p, jnp.zeros((4, 7 + 2 * extra))], axis=1)
    d_g = jnp.concatenate([jnp.sum(d_forces, axis=(0, 1)), d_generalized])
    if rails is None:
        return d_g
    d_rail = -jnp.einsum("sdi,spim->sdm", axes, d_forces).reshape(4, -1)
    return d_g, d_rail


def _rails_rate(track, rails, patches, patch_forces):
    """``(wdot, wddot)`` (W, 2, 2) of a flexible track's rails at ``rails = (w, wdot)``
    under the wheels' patch forces (:mod:`jaxrail.track.flexible`)."""
    loads = jax.vmap(lambda p, f: rail_loads(track, p, f))(patches, patch_forces)
    deflection, rate = rails
    return rate, track.support.accelerations(deflection, rate, loads)


class VehicleLoads(AbstractLoads):
    """The loads on a vehicle's bodies with the vehicle's system: the one term of the
    multibody solve (:class:`~jaxrail.multibody.AbstractLoads`; the system and its
    parameters are ``vehicle.system`` and ``params.system``, so they enter once).
    ``loads(t, q, qdot)`` returns forces and torques ``(n, 3)`` [N, N m], global, at
    the body centres (the ``external`` hook of :func:`jaxrail.multibody.accelerations`).

    Fields: vehicle, params (:class:`VehicleParams`, traced), track, model (the
    contact model), drive (a :class:`~jaxrail.vehicles.drive.SpeedDrive` holding the
    speed, a :class:`~jaxrail.vehicles.drive.ConstantForce`, or None: the vehicle
    coasts).
    """

    vehicle: Vehicle
    params: VehicleParams
    track: object
    model: object = eqx.field(default_factory=OnlineContact)
    drive: object = None

    @property
    def system(self):
        """The vehicle's multibody :class:`~jaxrail.multibody.System`."""
        return self.vehicle.system

    @property
    def system_params(self):
        """Its :class:`~jaxrail.multibody.SystemParams`, ``params.system``."""
        return self.params.system

    def _driven(self, t, qdot, forces):
        return forces if self.drive is None else self.drive.add_to(t, qdot, forces)

    def __call__(self, t, q, qdot):
        forces, torques = contact_loads(self.vehicle, self.params, self.track, q, qdot,
                                        self.model)[:2]
        return self._driven(t, qdot, forces), torques

    def coupled(self, t, q, qdot, rails):
        """On a flexible track (``track.support``): ``(forces, torques, (wdot,
        wddot))``, the loads of ``__call__`` with the rails at ``rails = (w, wdot)``
        (W, 2, 2) [m, m/s], and the rails' derivatives (:mod:`jaxrail.track.flexible`),
        from one contact evaluation."""
        forces, torques, patches, patch_forces = contact_loads(
            self.vehicle, self.params, self.track, q, qdot, self.model, rails)
        return (self._driven(t, qdot, forces), torques,
                _rails_rate(self.track, rails, patches, patch_forces))

    def linearised(self, t, q, qdot, rails=None, jacobian=True):
        """``(forces, torques, bodies, blocks)``: the loads of ``__call__``, the
        wheelset body indices and each wheelset's load Jacobian (W, 7, 14)
        (:func:`wheelset_load_jacobian`), from one contact evaluation. ``jacobian``: a
        bool, which may be traced, or a tuple of them that must all hold
        (:func:`~jaxrail.multibody.imex.stiff_jacobian`): where it is False the blocks
        are zeros, not computed.

        On a flexible track, with the rails at ``rails = (w, wdot)`` (W, 2, 2):
        ``(forces, torques, rails_dot, bodies, blocks, rail_rows)``, with the rails'
        derivatives as :meth:`coupled`, ``blocks`` (W, 7, 22) by each wheelset's (q,
        w, qdot, wdot) and ``rail_rows`` (W, 4, 22): the rails' accelerations
        (:class:`~jaxrail.track.flexible.FlexibleTrack`) by the same columns."""
        forces, torques, patches, patch_forces = contact_loads(
            self.vehicle, self.params, self.track, q, qdot, self.model, rails)
        rails_rate = None if rails is None else _rails_rate(self.track, rails, patches,
                                                            patch_forces)
        forces = self._driven(t, qdot, forces)
        index = np.asarray(self.vehicle.wheelsets)
        bodies = q.reshape(-1, 7)[index], qdot.reshape(-1, 7)[index], torques[index]
        contact = self.params.contact
        if rails is None:
            blocks = computed_when(jacobian, lambda: jax.vmap(
                lambda x, a, b, m: wheelset_load_jacobian(contact, x, a, b, m))(patches, *bodies))
            return forces, torques, self.vehicle.wheelsets, blocks
        axes = jax.vmap(lambda x: rail_axes(self.track, x))(patches)
        blocks, on_rails = computed_when(jacobian, lambda: jax.vmap(
            lambda x, a, b, m, w, v, u: wheelset_load_jacobian(contact, x, a, b, m, (w, v), u))(
                patches, *bodies, *rails, axes))
        support = self.track.support
        stiffness, damping, mass = (jnp.tile(x, 2) for x in (support.stiffness,
                                                             support.damping, support.mass))
        own = jnp.zeros((4, 22)).at[:, 7:11].set(-jnp.diag(stiffness)).at[:, 18:22].set(
            -jnp.diag(damping))
        rail_rows = (on_rails + own) / mass[:, None]
        return forces, torques, rails_rate, self.vehicle.wheelsets, blocks, rail_rows


def vehicle_accelerations(vehicle: Vehicle, params: VehicleParams, track, t, q, qdot,
                          model=None, drive=None, elements=None):
    """``qddot`` (7 n,) of eq. (19) with gravity, the suspension, the wheel-rail loads of
    ``model`` (default :class:`OnlineContact`) and ``drive`` (:class:`VehicleLoads`).
    ``elements``: the force elements' internal states ``{kind: (k, r)}``
    (:class:`~jaxrail.multibody.State`), needed where the vehicle has such elements."""
    loads = VehicleLoads(vehicle, params, track, resolve_contact_model(model), drive)
    return accelerations(loads.system, loads.system_params, t, q, qdot, loads, elements)[0]
