"""Wheelset poses relative to the track.

A pose is ``(position, rotation)``: the wheelset centre [m] and a (3, 3) matrix whose
columns are the wheelset axes (forward, axle to the left, up) in global components.
"""

import jax.numpy as jnp

from ..track import centreline_and_frame


def rotation_x(angle):
    """Rotation by ``angle`` [rad] about x (roll, right-handed)."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rotation_y(angle):
    """Rotation by ``angle`` [rad] about y (pitch, right-handed)."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rotation_z(angle):
    """Rotation by ``angle`` [rad] about z (yaw, right-handed: positive turns left)."""
    c, s = jnp.cos(angle), jnp.sin(angle)
    return jnp.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def wheelset_pose(track, s, lateral=0.0, vertical=0.46, roll=0.0, yaw=0.0, pitch=0.0):
    """Pose of a wheelset given in the track frame at arc length ``s`` [m].

    Arguments:
        lateral: shift of the centre along the track's lateral axis, positive left [m].
        vertical: height of the centre above the track plane [m] (about the rolling
            radius when the wheels touch the rails).
        roll, yaw, pitch: rotations [rad] relative to the track frame, applied as
            ``track_frame @ Rz(yaw) @ Rx(roll) @ Ry(pitch)``; roll positive lifts the
            left wheel (right-handed about the forward axis), yaw positive turns the
            wheelset to the left. Pitch is the wheel's rotation about its axle.

    Returns ``(position (3,), rotation (3, 3))``.
    """
    centre, axes = centreline_and_frame(track, s)
    position = centre + lateral * axes[:, 1] + vertical * axes[:, 2]
    rotation = axes @ rotation_z(yaw) @ rotation_x(roll) @ rotation_y(pitch)
    return position, rotation
