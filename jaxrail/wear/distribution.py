"""Wear volumes spread over a profile's lateral coordinate.

A profile's wear is the height it loses, ``dh(y)`` [m], on a grid of its lateral
coordinate ``y`` (the profile's own, :mod:`jaxrail.profiles`: positive toward the field
side). Removing ``dh`` from the height function removes the cross-section
``integral dh dy``, so a volume ``V`` taken from a wheel of rolling circumference
``2 pi r``, or from a rail along a run of length ``D``, lowers the profile by a
``dh`` whose integral is ``V / (2 pi r)`` or ``V / D``: the spreading conserves the
volume exactly (linear weights onto the two nearest grid nodes, points beyond the grid
on its end nodes; :func:`deposit`).

The height is radial on a wheel and vertical on a rail: on the flange, wear normal to
the surface of depth ``d`` lowers the height by ``d / cos(slope)``.
"""

import jax.numpy as jnp
import numpy as np


def lateral_grid(domain, spacing=0.5e-3) -> np.ndarray:
    """Nodes [m] every ``spacing`` [m] (about) over ``domain`` ``(y_min, y_max)`` [m] of a
    profile, both ends included."""
    low, high = (float(v) for v in domain)
    count = max(2, int(round((high - low) / spacing)) + 1)
    return np.linspace(low, high, count)


def deposit(nodes, positions, volumes):
    """Volumes (K,) at the grid ``nodes`` (K,) [m, uniform] of ``volumes`` (...) placed
    at ``positions`` (...) [m]: each split between its two nearest nodes by linear
    weights (beyond the grid: all on the end node). The total is kept exactly."""
    nodes = jnp.asarray(nodes, dtype=jnp.float64)
    spacing = nodes[1] - nodes[0]
    u = jnp.clip((jnp.ravel(positions) - nodes[0]) / spacing, 0.0, nodes.shape[0] - 1.0)
    lower = jnp.clip(jnp.floor(u), 0, nodes.shape[0] - 2)
    upper_share = u - lower
    volumes = jnp.ravel(volumes)
    lower = lower.astype(jnp.int32)
    out = jnp.zeros(nodes.shape, dtype=jnp.float64)
    out = out.at[lower].add(volumes * (1.0 - upper_share))
    return out.at[lower + 1].add(volumes * upper_share)


def height_loss(nodes, volume_at_nodes, length):
    """The height loss dh (K,) [m] at the ``nodes`` of the volumes there (K,) [m^3]
    taken along ``length`` [m] of surface (a wheel's circumference, a rail's run):
    ``sum(dh) * spacing * length`` is the total volume."""
    spacing = jnp.asarray(nodes[1] - nodes[0], dtype=jnp.float64)
    return volume_at_nodes / (spacing * length)


def strip_positions(contact_y, contact_angle, strip_offset, side_sign):
    """The profile lateral coordinate [m] of each strip (..., strips) of a patch whose
    contact point lies at ``contact_y`` [m] on the profile with contact angle
    ``contact_angle`` [rad]: the strip's offset along the contact frame's ``l`` (to the
    left of travel), tilted by the contact angle, toward the field side on the left
    wheel or rail (``side_sign`` +1) and toward the track centre on the right one (-1)."""
    return contact_y[..., None] + side_sign * strip_offset * jnp.cos(contact_angle)[..., None]


