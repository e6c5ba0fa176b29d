"""Normal force laws: formulas, edges, gradients, jit/vmap, and a diffrax drop test that
measures each law's effective coefficient of restitution."""

import diffrax
import jax
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxrail.contact.normal import (
    Eq17,
    Flores,
    Hertz,
    HuntCrossley,
    LankaraniNikravesh,
    NormalLaw,
)

# --------------------------------------------------------------------------------------
# Independent NumPy statements of the laws (reference section 7 / paper eq. 17).


def _eq17_numpy(k, d, dd, ce, v0, n):
    if d <= 0:
        return 0.0
    if dd <= -v0:
        return k * d**n * ce
    if dd >= v0:
        return k * d**n
    r = (dd + v0) / (2 * v0)
    return k * d**n * (ce + (1 - ce) * (3 * r**2 - 2 * r**3))


ALPHA = {  # f = K d^n (1 + alpha dd / v_impact)
    "HuntCrossley": lambda c: 3 * (1 - c) / 2,  # chi = 3 K (1 - c)/(2 v_impact)
    "LankaraniNikravesh": lambda c: 3 * (1 - c**2) / 4,
    "Flores": lambda c: 8 * (1 - c) / (5 * c),
}
DAMPED = {"HuntCrossley": HuntCrossley, "LankaraniNikravesh": LankaraniNikravesh, "Flores": Flores}


def _damped_numpy(name, k, d, dd, c, n, v_impact):
    if d <= 0:
        return 0.0
    return max(k * d**n * (1 + ALPHA[name](c) * dd / v_impact), 0.0)


# --------------------------------------------------------------------------------------
# Formulas and edge cases.

_DELTA = np.array([2e-5, 1e-4, 3e-4])
_RATE = np.array([-0.02, -0.01, -0.004, 0.0, 0.003, 0.01, 0.5])


def _batched(law):
    """jit(vmap) over a batch of contacts (stiffness, penetration, rate)."""
    return jax.jit(jax.vmap(lambda k, d, dd: law.force(k, d, dd)))


def test_eq17_matches_the_paper_formula_under_jit_and_vmap():
    law = Eq17(restitution=0.5, v0=0.01, exponent=1.5)
    d, dd = np.meshgrid(_DELTA, _RATE)
    k = np.full(d.size, 1e11)
    got = _batched(law)(k, d.ravel(), dd.ravel())
    want = [_eq17_numpy(1e11, x, y, 0.5, 0.01, 1.5) for x, y in zip(d.ravel(), dd.ravel())]
    np.testing.assert_allclose(got, want, rtol=1e-14)
    # At rest (rate 0) it is (1 + c_e)/2 of Hertz (finding 3 of reference section 7).
    at_rest = law.force(1e11, 1e-4, 0.0)
    assert float(at_rest) == pytest.approx(0.75 * 1e11 * 1e-4**1.5, rel=1e-14)


@pytest.mark.parametrize("name", list(DAMPED))
def test_damped_laws_match_formulas_under_jit_and_vmap(name):
    law = DAMPED[name](restitution=0.6, exponent=1.5, impact_velocity=0.01)
    d, dd = np.meshgrid(_DELTA, _RATE)
    k = np.full(d.size, 1e11)
    got = _batched(law)(k, d.ravel(), dd.ravel())
    want = [_damped_numpy(name, 1e11, x, y, 0.6, 1.5, 0.01) for x, y in zip(d.ravel(), dd.ravel())]
    np.testing.assert_allclose(got, want, rtol=1e-14)
    # An explicit impact velocity overrides the field.
    override = DAMPED[name](restitution=0.6).force(1e11, 1e-4, -0.004, impact_velocity=0.01)
    assert float(override) == pytest.approx(_damped_numpy(name, 1e11, 1e-4, -0.004, 0.6, 1.5, 0.01))
    # Fast separation would pull (adhesion): clipped to exactly 0.
    assert float(law.force(1e11, 1e-4, -100.0)) == 0.0


def test_hertz_law():
    got = _batched(Hertz(1.5))(np.full(3, 2e10), _DELTA, np.array([-1.0, 0.0, 1.0]))
    np.testing.assert_allclose(got, 2e10 * _DELTA**1.5, rtol=1e-15)


ALL_LAWS = [
    Hertz(),
    Eq17(),
    Eq17.from_restitution(0.7, v0=0.005),
    HuntCrossley(0.7),
    LankaraniNikravesh(0.7),
    Flores(0.7),
]


@pytest.mark.parametrize("law", ALL_LAWS, ids=lambda x: type(x).__name__)
def test_no_contact_gives_zero_force_and_zero_finite_gradient(law):
    def f(inputs, law):
        k, d, dd = inputs
        return law.force(k, d, dd)

    grad = jax.jit(jax.vmap(jax.grad(f, argnums=(0, 1)), in_axes=(0, None)))
    k = jnp.full(4, 1e11)
    d = jnp.array([0.0, -1e-4, 0.0, -1e-9])
    dd = jnp.array([0.0, 5.0, -5.0, 1e-3])
    assert np.all(np.asarray(jax.vmap(f, in_axes=(0, None))((k, d, dd), law)) == 0.0)
    g_inputs, g_law = grad((k, d, dd), law)
    for leaf in jax.tree_util.tree_leaves((g_inputs, g_law)):
        assert np.all(np.asarray(leaf) == 0.0)


@pytest.mark.parametrize("law", ALL_LAWS, ids=lambda x: type(x).__name__)
def test_gradients_vs_central_differences(law):
    # Flatten (stiffness, penetration, rate, law parameters) into one vector.
    params, rebuild = jax.flatten_util.ravel_pytree(law)

    @jax.jit
    def f(x):
        return rebuild(x[3:]).force(x[0], x[1], x[2])

    grad = jax.jit(jax.grad(f))
    for rate in (-0.003, 0.002, 0.02):  # inside and outside the eq. (17) blend
        x = np.concatenate([[1e11, 1e-4, rate], np.asarray(params)])
        h = 1e-6 * np.maximum(np.abs(x), 1e-3)
        fd = np.array(
            [(f(x + h[i] * e) - f(x - h[i] * e)) / (2 * h[i]) for i, e in enumerate(np.eye(len(x)))]
        )
        np.testing.assert_allclose(grad(x), fd, rtol=1e-6, atol=1e-9 * float(np.max(np.abs(fd))))


def test_eq17_equivalent_damping_near_rest():
    # c_eq = d f / d rate at rate 0 = K d^n (1 - c_e) s'(1/2) / (2 v0), s'(1/2) = 1.5.
    law = Eq17(restitution=0.5, v0=1e-3)
    c_eq = jax.grad(lambda r: law.force(9.29e10, 6.6e-5, r))(0.0)
    n_static = 9.29e10 * 6.6e-5**1.5
    assert float(c_eq) == pytest.approx(n_static * 0.5 * 1.5 / (2 * 1e-3), rel=1e-13)


def test_vmap_over_a_batch_of_laws():
    restitution = jnp.array([0.3, 0.5, 0.8])
    forces = jax.jit(jax.vmap(lambda c: Eq17(c, 0.01).force(1e11, 1e-4, -0.005)))(restitution)
    want = [_eq17_numpy(1e11, 1e-4, -0.005, c, 0.01, 1.5) for c in (0.3, 0.5, 0.8)]
    np.testing.assert_allclose(forces, want, rtol=1e-14)
    law = LankaraniNikravesh(restitution)  # array-valued fields broadcast too
    np.testing.assert_allclose(
        law.force(1e11, 1e-4, 0.05),
        [_damped_numpy("LankaraniNikravesh", 1e11, 1e-4, 0.05, c, 1.5, 0.1)
         for c in (0.3, 0.5, 0.8)],
        rtol=1e-14,
    )


def test_constructors_validate_and_convert():
    law = Eq17.from_restitution(0.8)
    assert float(law.restitution) == pytest.approx(0.64, rel=1e-15)
    assert float(law.effective_restitution) == pytest.approx(0.8, rel=1e-15)
    assert law.v0.dtype == jnp.float64 and law.exponent.dtype == jnp.float64
    assert isinstance(law, NormalLaw)
    with pytest.raises(ValueError, match="restitution"):
        Eq17(restitution=1.2)
    with pytest.raises(ValueError, match="v0"):
        Eq17(v0=0.0)
    with pytest.raises(ValueError, match="exponent"):
        Hertz(exponent=-1.0)
    with pytest.raises(ValueError, match="restitution"):
        Flores(restitution=0.0)
    with pytest.raises(ValueError, match="impact_velocity"):
        LankaraniNikravesh(0.5, impact_velocity=-0.1)
    with pytest.raises(ValueError, match="restitution"):
        HuntCrossley(jnp.array([0.5, 1.5]))


# --------------------------------------------------------------------------------------
# Drop test: a unit mass hits a Hertzian contact (K = 1 N/m^1.5) at 1 m/s; every case is
# one row of a single ODE system, so diffrax compiles once. After the mass leaves the
# contact its velocity is constant: the final velocity is the rebound velocity.

RESTITUTION = (0.3, 0.5, 0.8, 0.95, 0.99)
EQ17_CE = (0.3, 0.5, 0.8)
V_IN = 1.0


def _cases():
    ce = jnp.array(EQ17_CE)
    cases = [
        ("hertz", Hertz(), False),
        ("eq17", Eq17(ce, v0=0.01 * V_IN), False),
        ("eq17_from_e", Eq17.from_restitution(jnp.array([0.6]), v0=0.01 * V_IN), False),
        ("eq17_flipped", Eq17(ce, v0=0.01 * V_IN), True),
    ]
    for name, cls in DAMPED.items():
        cases.append((name, cls(jnp.array(RESTITUTION), impact_velocity=V_IN), False))
    return cases


CASES = _cases()
SIZES = {"hertz": 1, "eq17": 3, "eq17_from_e": 1, "eq17_flipped": 3}
SIZES.update({name: len(RESTITUTION) for name in DAMPED})


@jax.jit
def _drop(laws):
    def rhs(t, y, args):
        forces, start = [], 0
        for (name, _, flipped), law in zip(CASES, laws):
            rows = slice(start, start + SIZES[name])
            rate = -y[rows, 1] if flipped else y[rows, 1]  # flipped: rate of a gap
            forces.append(law.force(1.0, y[rows, 0], rate))
            start += SIZES[name]
        return jnp.stack([y[:, 1], -jnp.concatenate(forces)], axis=-1)

    rows = sum(SIZES.values())
    y0 = jnp.stack([jnp.zeros(rows), jnp.full(rows, V_IN)], axis=-1)
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(rhs),
        diffrax.Tsit5(),
        t0=0.0,
        t1=25.0,
        dt0=1e-3,
        y0=y0,
        stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-12),
        max_steps=20000,
    )
    return sol.ys[-1]


@pytest.fixture(scope="module")
def rebound():
    final = np.asarray(_drop([law for _, law, _ in CASES]))
    assert np.all(final[:, 0] < -1.0)  # every case has left the contact
    out, start = {}, 0
    for name, _, _ in CASES:
        out[name] = -final[start : start + SIZES[name], 1]
        start += SIZES[name]
    return out


def _scipy_rebound(alpha):
    """Rebound speed of the damped law by an independent integrator (DOP853, event)."""

    def rhs(t, y):
        d, v = y
        f = max(d, 0.0) ** 1.5 * (1 + alpha * v / V_IN) if d > 0 else 0.0
        return [v, -max(f, 0.0)]

    def leaves(t, y):
        return y[0] + 1e-12 if t > 0.1 else 1.0

    leaves.terminal, leaves.direction = True, -1
    sol = solve_ivp(rhs, (0, 60), [0, V_IN], method="DOP853", rtol=1e-12, atol=1e-14, events=leaves)
    return -sol.y[1, -1]


def test_drop_hertz_is_elastic(rebound):
    assert rebound["hertz"][0] == pytest.approx(V_IN, rel=1e-7)


def test_drop_eq17_effective_restitution_is_sqrt_ce(rebound):
    np.testing.assert_allclose(rebound["eq17"] / V_IN, np.sqrt(EQ17_CE), rtol=5e-3)
    # Measured: within 1e-4 at v0 = 0.01 v_in (documented).
    np.testing.assert_allclose(rebound["eq17"] / V_IN, np.sqrt(EQ17_CE), rtol=1e-4)
    # from_restitution(e) rebounds with e itself.
    assert rebound["eq17_from_e"][0] / V_IN == pytest.approx(0.6, rel=1e-4)


def test_drop_flipped_sign_convention_gains_energy(rebound):
    # Passing the rate of a signed gap swaps loading and unloading: rebound 1/sqrt(c_e).
    assert np.all(rebound["eq17_flipped"] > V_IN)
    np.testing.assert_allclose(rebound["eq17_flipped"] / V_IN, 1 / np.sqrt(EQ17_CE), rtol=1e-4)
    assert np.all(rebound["eq17"] < V_IN)


@pytest.mark.parametrize("name", list(DAMPED))
def test_drop_damped_laws(rebound, name):
    measured = rebound[name] / V_IN
    reference = np.array([_scipy_rebound(ALPHA[name](c)) for c in RESTITUTION]) / V_IN
    np.testing.assert_allclose(measured, reference, rtol=1e-6)
    # All three approach their nominal restitution as c_e -> 1.
    assert measured[-1] == pytest.approx(0.99, abs=1e-3)
    assert measured[-2] == pytest.approx(0.95, abs=5e-3)


def test_drop_documented_restitution_values(rebound):
    # The measured values quoted in docs/normal-forces.md (c_e = 0.3, 0.5, 0.8, 0.95, 0.99).
    documented = {
        "HuntCrossley": [0.5813, 0.6630, 0.8329, 0.9524, 0.9901],
        "LankaraniNikravesh": [0.6842, 0.7252, 0.8471, 0.9535, 0.9901],
        "Flores": [0.2562, 0.4704, 0.7885, 0.9468, 0.9893],
    }
    for name, values in documented.items():
        np.testing.assert_allclose(rebound[name] / V_IN, values, atol=6e-5)


def test_drop_never_gains_energy(rebound):
    for name, _, flipped in CASES:
        if not flipped:  # 1e-7: the integration error of the elastic (Hertz) case
            assert np.all(rebound[name] <= V_IN * (1 + 1e-7)), name
