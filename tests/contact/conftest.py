import numpy as np
import pytest


@pytest.fixture
def central_jacobian():
    """``jacobian(f, v, steps)``: the central-difference Jacobian (m, n) of ``f`` (n,) ->
    (m,) at ``v``, with step ``steps[i]`` in argument ``i``."""

    def jacobian(f, v, steps):
        columns = []
        for i, h in enumerate(steps):
            e = np.zeros(len(v))
            e[i] = h
            columns.append((np.array(f(v + e)) - np.array(f(v - e))) / (2 * h))
        return np.stack(columns, axis=1)

    return jacobian
