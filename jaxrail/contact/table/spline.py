"""Quadratic B-splines along a table's pose axes (lateral, yaw, roll): the
coefficients through the node values (prefiltering, at build time) and the weights of a
pose's 3 x 3 x 3 block of coefficients (at lookup)."""

import jax.numpy as jnp
import numpy as np

from .grid import Axis, ContactTable, TableGrid


def _pose_axes(grid: TableGrid):
    return (grid.lateral, grid.yaw, grid.roll)


def _spline_matrix(count):
    """(count + 2, count + 2) system for the coefficients of a uniform quadratic
    B-spline through ``count`` node values, with a zero third difference of the
    coefficients at both ends (rows 0 and -1), so that quadratics are reproduced
    exactly up to the ends (a yaw axis of five nodes is mostly ends); two nodes give
    the line through them."""
    a = np.zeros((count + 2, count + 2))
    end = (-1.0, 3.0, -3.0, 1.0) if count > 2 else (1.0, -2.0, 1.0)  # two nodes: a line
    a[0, :len(end)] = end
    a[-1, -len(end):] = end
    for i in range(count):
        a[i + 1, i:i + 3] = (0.125, 0.75, 0.125)
    return a


def _prefilter(values, grid: TableGrid):
    """Quadratic B-spline coefficients (2, lateral + 2, yaw + 2, roll + 2, approach, P, F)
    of ``values`` (2, lateral, yaw, roll, approach, P, F) along the pose axes: the spline
    through every node value (C1, third-order accurate); one-node axes stay as they
    are. The approach axis keeps its node values (:func:`table_patches` interpolates
    along it in the wheel's vertical position)."""
    for dim, axis in enumerate(_pose_axes(grid), start=1):
        if axis.count < 2:
            continue
        moved = np.moveaxis(values, dim, 0)
        rhs = np.concatenate([np.zeros((1,) + moved.shape[1:]), moved,
                              np.zeros((1,) + moved.shape[1:])])
        solved = np.linalg.solve(_spline_matrix(axis.count), rhs.reshape(len(rhs), -1))
        values = np.moveaxis(solved.reshape(rhs.shape), 0, dim)
    return values


def _spline_weights(axis: Axis, x):
    """Start of the 3-coefficient block and the quadratic B-spline weights of ``x``
    (clamped to the axis' span); a one-node axis gives (0, [1])."""
    if axis.count == 1:
        return jnp.zeros((), dtype=jnp.int32), jnp.ones((1,))
    u = jnp.clip((x - axis.start) / axis.step, 0.0, axis.count - 1.0)
    i = jnp.clip(jnp.round(u), 0, axis.count - 1)
    t = u - i
    w = jnp.stack([0.5 * (0.5 - t) ** 2, 0.75 - t * t, 0.5 * (0.5 + t) ** 2])
    return i.astype(jnp.int32), w


def _pose_weights(table: ContactTable, lateral, yaw, roll):
    """The 3 x 3 x 3 block of B-spline coefficients around a pose: its first
    (lateral, yaw, roll) coefficient indices (int32 scalars), its size along each axis
    (3, or 1 on a one-node axis) and the weights (27,) of its coefficients in their
    order in the table: the product of the quadratic B-spline weights along lateral,
    yaw and roll (C1)."""
    starts, weight = [], jnp.ones(())
    for axis, x in zip(_pose_axes(table.grid), (lateral, yaw, roll)):
        start, w = _spline_weights(axis, x)
        starts.append(start)
        weight = weight[..., None] * w
    return tuple(starts), weight.shape, weight.reshape(-1)
