"""Creepages (longitudinal, lateral, spin) from rigid-body velocities at a contact.

Contact frame (a 3x3 matrix whose **columns** are unit vectors in the global frame):

- ``t`` (column 0), longitudinal: tangent to the rail along the **direction of travel**
  (the rolling direction);
- ``l`` (column 1), lateral: in the contact tangent plane, to the **left** of ``t``;
- ``n`` (column 2) = ``t x l``, normal: **out of the rail into the wheel** (upward for a
  tread contact). ``(t, l, n)`` is right-handed.

Creepages follow Kalker (docs/design.md §3): with ``v_slip`` the velocity of the
wheel's material point at the contact minus the rail's,

    xi = v_slip . t / V,    eta = v_slip . l / V,    phi = (omega_w - omega_r) . n / V,

``V`` the rolling speed. In this frame the rigid slip at a point ``(x, y)`` of the
contact patch is ``V (xi - phi y, eta + phi x)``, ``x`` along ``t``: the convention in
which Kalker's c23 > 0 and Polach's ``s_y + phi a`` are written.

Worked signs (wheelset moving at speed V along +x, axle along +y, wheel radius r):

- pure rolling: angular velocity ``+V/r`` about +y (the top of the wheel moves
  forward) gives zero creepage;
- yaw angle ``alpha`` (positive nose to the left, about +z): ``xi = 1 - cos alpha``,
  ``eta = -sin alpha`` at both wheels;
- coned tread with contact angle gamma: ``n = (0, -sin gamma, cos gamma)`` at the left
  wheel (leaning towards the track centre), so ``phi = -sin(gamma)/r``; the right wheel
  mirrors it, ``phi = +sin(gamma)/r``.

Rolling speed: by default the magnitude of the wheel centre's velocity along ``t``,
regularised as ``V = sqrt((v_w . t)^2 + v_reg^2)`` so that creepages stay finite (and
smooth) at standstill. Its relative effect is ``v_reg^2 / (2 (v_w . t)^2)``: 5e-5 at
1 m/s for the default 0.01 m/s. Below ``v_reg`` the creepages become slip velocity
divided by ``v_reg``; the creep force then acts as a stiff viscous damper
(``G a b c11 / v_reg`` N s/m), not as dry friction. The model assumes forward rolling
(``t`` along the motion); for backward running, flip ``t`` and ``l``.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float


def _vector(x, name):
    x = jnp.asarray(x, dtype=jnp.float64)
    if x.shape != (3,):
        raise ValueError(f"{name} must be a 3-vector (shape (3,)), got shape {x.shape}")
    return x


def creepages(
    wheel_velocity: Float[ArrayLike, "3"],
    wheel_angular_velocity: Float[ArrayLike, "3"],
    wheel_centre: Float[ArrayLike, "3"],
    contact_point: Float[ArrayLike, "3"],
    contact_frame: Float[ArrayLike, "3 3"],
    rail_velocity: Float[ArrayLike, "3"] | None = None,
    rail_angular_velocity: Float[ArrayLike, "3"] | None = None,
    rolling_speed: Float[ArrayLike, ""] | None = None,
    speed_regularisation: Float[ArrayLike, ""] = 0.01,
) -> tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]:
    """Kalker creepages ``(xi, eta, phi)`` of a wheel on a rail at one contact point.

    **Arguments** (global frame, SI; one contact, vmap for many):

    - `wheel_velocity`: velocity of the wheel centre [m/s], shape (3,).
    - `wheel_angular_velocity`: angular velocity of the wheel [rad/s], shape (3,).
    - `wheel_centre`: position of the wheel centre [m], shape (3,) (the reference point
      of `wheel_velocity`).
    - `contact_point`: contact point [m], shape (3,).
    - `contact_frame`: shape (3, 3), columns ``t, l, n`` (see the module docstring).
    - `rail_velocity`: velocity of the rail's material point at the contact [m/s],
      default zero (rigid fixed track).
    - `rail_angular_velocity`: angular velocity of the rail [rad/s], default zero.
    - `rolling_speed`: V [m/s] to divide by; default ``sqrt((v_w . t)^2 + v_reg^2)``.
    - `speed_regularisation`: v_reg [m/s] > 0 of the default rolling speed.

    **Returns** ``(xi, eta, phi)``: longitudinal and lateral creepage [-], spin [1/m].
    """
    v_w = _vector(wheel_velocity, "wheel_velocity")
    omega_w = _vector(wheel_angular_velocity, "wheel_angular_velocity")
    centre = _vector(wheel_centre, "wheel_centre")
    point = _vector(contact_point, "contact_point")
    frame = jnp.asarray(contact_frame, dtype=jnp.float64)
    if frame.shape != (3, 3):
        raise ValueError(
            f"contact_frame must have shape (3, 3) (columns t, l, n), got {frame.shape}"
        )
    v_r = jnp.zeros(3) if rail_velocity is None else _vector(rail_velocity, "rail_velocity")
    omega_r = (
        jnp.zeros(3)
        if rail_angular_velocity is None
        else _vector(rail_angular_velocity, "rail_angular_velocity")
    )
    if isinstance(speed_regularisation, (int, float)) and speed_regularisation <= 0.0:
        raise ValueError(f"speed_regularisation must be > 0, got {speed_regularisation}")

    t, l, n = frame[:, 0], frame[:, 1], frame[:, 2]
    slip = v_w + jnp.cross(omega_w, point - centre) - v_r
    if rolling_speed is None:
        v_long = jnp.dot(v_w, t)
        v_reg = jnp.asarray(speed_regularisation, dtype=jnp.float64)
        speed = jnp.sqrt(v_long * v_long + v_reg * v_reg)
    else:
        speed = jnp.asarray(rolling_speed, dtype=jnp.float64)
    return (
        jnp.dot(slip, t) / speed,
        jnp.dot(slip, l) / speed,
        jnp.dot(omega_w - omega_r, n) / speed,
    )
