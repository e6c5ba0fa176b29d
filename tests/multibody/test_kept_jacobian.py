"""The pieces IMEX uses to keep a load Jacobian across steps (jaxrail.multibody.imex):
a body's turn about its own y axis (``_twist``) and a Jacobian carried by it
(``StiffJacobian.turned``), against a turn built by hand and a dense S J S^-1."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxrail.multibody import quaternion as qt
from jaxrail.multibody.imex import StiffJacobian, _twist

jax.config.update("jax_enable_x64", True)

X, Y, Z = (jnp.eye(3)[i] for i in range(3))


def test_the_twist_is_the_turn_about_the_bodys_own_y_axis():
    """From a yawed, rolled pose, turned about its own y by 0.3 rad and tilted about
    its own x by 0.02 rad: the twist is the 0.3 rad about y (up to the quaternion's
    sign). Taken in the global frame (now * conj(then)) it would not be."""
    then = qt.multiply(qt.from_axis_angle(Z, 0.4), qt.from_axis_angle(X, 0.3))
    turn = qt.from_axis_angle(Y, 0.3)
    now = qt.multiply(qt.multiply(then, turn), qt.from_axis_angle(X, 0.02))
    twist = np.asarray(_twist(then[None], now[None])[0])
    assert np.allclose(twist, turn, atol=1e-12) or np.allclose(twist, -turn, atol=1e-12)
    conj = then * jnp.array([1.0, -1.0, -1.0, -1.0])
    wrong = np.asarray(_twist(jnp.array([[1.0, 0, 0, 0]]), qt.multiply(now, conj)[None])[0])
    assert not np.allclose(np.abs(wrong), np.abs(turn), atol=1e-3)


def test_a_turned_jacobian_is_s_j_s_inverse():
    """Two stiff bodies (1 and 3 of 5) with 4 further states each (a flexible track's
    rails): ``turned`` equals S A S^T with S the identity but for the right product by
    each body's turn on its Euler parameters' rows, A_q and A_v random."""
    n, bodies, r = 5, (1, 3), 4
    n7 = 7 * n
    columns = tuple(c for j, b in enumerate(bodies)
                    for c in [7 * b + i for i in range(7)] + [n7 + r * j + i for i in range(r)])
    rows = n7 + r * len(bodies)
    key_q, key_v = jax.random.split(jax.random.key(0))
    a_q = jax.random.normal(key_q, (rows, len(columns)))
    a_v = jax.random.normal(key_v, (rows, len(columns)))
    turns = jnp.stack([qt.from_axis_angle(Y, 0.7), qt.from_axis_angle(Y, -1.1)])
    s = np.eye(rows)
    for b, turn in zip(bodies, turns):
        # the right product by the turn, column by column from quaternion.multiply
        right = np.stack([np.asarray(qt.multiply(jnp.eye(4)[i], turn)) for i in range(4)], 1)
        s[7 * b + 3:7 * b + 7, 7 * b + 3:7 * b + 7] = right
    s_columns = s[np.ix_(columns, columns)]
    carried = StiffJacobian(columns, a_q, a_v, len(bodies)).turned(turns)
    for before, after in ((a_q, carried.a_q), (a_v, carried.a_v)):
        np.testing.assert_allclose(after, s @ np.asarray(before) @ s_columns.T, rtol=0,
                                   atol=1e-12)
