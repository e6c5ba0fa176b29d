"""A single free wheelset rolled along the track by :func:`~jaxrail.simulation.simulate`:
for tests and studies (Klingel's kinematic hunting, contact dynamics). The vehicle is
:func:`jaxrail.vehicles.single_wheelset`."""

from ..contact.pose import wheelset_pose
from ..contact.search import SearchConfig
from ..multibody import join_coordinates, quaternion, velocities_from_twists
from ..vehicles import ContactParameters, single_wheelset, touching_height
from .options import SolverOptions
from .run import simulate


def simulate_single_wheelset(wheel, track, speed, lateral, t1,
                             n_outputs=201, contact=None, s0=10.0,
                             config=SearchConfig(), rtol=1e-6, atol=1e-9, max_steps=400_000,
                             contact_model=None, integrator="tsit5", progress=False):
    """Roll a free wheelset of ``wheel`` profile along ``track`` (on its rails) from arc
    length ``s0`` [m] with :func:`jaxrail.simulation.simulate`.

    It starts at the touching height, shifted by ``lateral`` [m] (positive left), moving
    at ``speed`` [m/s] and spinning at ``speed / rolling radius`` of the centred contact,
    and runs for ``t1`` [s] with ``n_outputs`` equally spaced outputs, Tsit5 and the PID
    controller (``rtol``, ``atol``). ``contact``: :class:`ContactParameters` (default
    ones). ``progress``: show the progress bar. Returns ``(result, (height, patches))``: the
    :class:`jaxrail.simulation.SimulationResult` and the centred touching height [m] and
    patches.
    """
    contact = ContactParameters() if contact is None else contact
    height, patches = touching_height(wheel, track, s0, config)
    vehicle, params = single_wheelset(wheel, contact, config)
    position, rotation = wheelset_pose(track, s0, lateral, height)
    q0 = join_coordinates(position[None, :], quaternion.from_rotation_matrix(rotation)[None, :])
    radius = patches.rolling_radius[0, 0]
    qdot0 = velocities_from_twists(q0, speed * rotation[:, 0][None, :],
                                   (speed / radius) * rotation[:, 1][None, :])
    options = SolverOptions(rtol=rtol, atol=atol, dt0=1e-4, max_steps=max_steps,
                            n_outputs=n_outputs, integrator=integrator, progress=progress)
    result = simulate(vehicle, params, track, t1, speed, initial=(q0, qdot0), options=options,
                      contact_model=contact_model)
    return result, (height, patches)
