"""The table spring and its interpolant (jaxrail.multibody.pchip, table_spring):
scipy's PCHIP as the reference, exactness at the table's points, monotonicity, C1,
the clearance's gap, gradients against central finite differences, and a spring-mass
system whose total energy is kept."""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

import jaxrail.multibody as mb
from jaxrail.multibody import forces as fc
from jaxrail.multibody import pchip

RNG = np.random.default_rng(11)
# A progressive rubber spring: soft in the middle, stiffening both ways, flat at the
# negative end (a zero slope and a repeated force test the monotone slopes).
X = np.array([-0.04, -0.03, -0.015, 0.0, 0.01, 0.02, 0.03])  # [m]
F = np.array([-6e4, -6e4, -1.5e4, 0.0, 4e3, 1.5e4, 5e4])  # [N]
CLEARANCE = 0.005  # [m]


def _kind_params(clearance=0.0, damping=0.0, x=X, f=F):
    spec = mb.TableSpring("ground", "mass", (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 1),
                          displacements=x, forces=f, clearance=clearance, damping=damping)
    return fc.FORCE_KINDS["table_spring"].params([spec], "force table_spring")


def _one(e):
    """The first element's parameters (the vmapped kernels see one element)."""
    return jax.tree.map(lambda a: a[0], e)


@jax.jit
def _law(e, s, sdot):
    kind = fc.FORCE_KINDS["table_spring"]
    return jax.vmap(lambda a, b: kind.law(a[None], b[None], _one(e))[0])(s, sdot)


@jax.jit
def _potential(e, s):
    return jax.vmap(lambda a: fc.FORCE_KINDS["table_spring"].potential(a[None], _one(e)))(s)


def test_interpolant_is_scipys_pchip_and_its_integral():
    """Slopes, values and integrals of random monotone tables against scipy's
    PchipInterpolator (1e-12 of the table's scale); beyond the ends the end slopes'
    lines; the integral's derivative is the value."""
    for m in (2, 3, 5, 8):
        x = np.cumsum(RNG.uniform(0.1, 1.0, m)) - 1.0
        y = np.cumsum(RNG.uniform(0.0, 3.0, m) * (RNG.uniform(size=m) > 0.3))
        d = pchip.monotone_slopes(x, y)
        ref = PchipInterpolator(x, y)
        np.testing.assert_allclose(d, ref.derivative()(x), rtol=1e-12, atol=1e-12)
        u = np.linspace(x[0] - 0.5, x[-1] + 0.5, 2001)
        xe, ye, de = (jnp.asarray(a) for a in pchip.extend_table(x, y, d, 10))
        value, integral = jax.jit(jax.vmap(
            lambda v: pchip.value_and_integral(xe, ye, de, v)))(u)
        slope = jax.jit(jax.vmap(jax.grad(
            lambda v: pchip.value_and_integral(xe, ye, de, v)[1])))(u)
        inside = (u >= x[0]) & (u <= x[-1])
        scale = np.abs(y).max() + 1.0
        np.testing.assert_allclose(value[inside], ref(u[inside]), atol=1e-12 * scale)
        antiderivative = ref.antiderivative()
        np.testing.assert_allclose(integral[inside],
                                   antiderivative(u[inside]) - antiderivative(x[0]),
                                   atol=1e-12 * scale)
        line = np.where(u < x[0], y[0] + d[0] * (u - x[0]), y[-1] + d[-1] * (u - x[-1]))
        np.testing.assert_allclose(value[~inside], line[~inside], atol=1e-12 * scale)
        np.testing.assert_allclose(slope, value, atol=1e-12 * scale)


def test_force_is_exact_at_the_points_monotone_and_c1():
    """With and without clearance: F equals the table at its points (1e-12 relative),
    never decreases on a fine grid, and its slope at each point is the PCHIP slope from
    both sides (one-sided difference quotients agree to 1e-5 of the largest slope);
    rounding on the table's flat interval wobbles by 1e-11 N."""
    slopes = pchip.monotone_slopes(X, F)
    for c in (0.0, CLEARANCE):
        e = _kind_params(clearance=c)
        s = X + c * np.sign(X)
        f = np.asarray(_law(e, s, np.zeros_like(s)))
        np.testing.assert_allclose(f, F, rtol=1e-12, atol=1e-12 * np.abs(F).max())
        grid = np.linspace(X[0] - 0.01 - c, X[-1] + 0.01 + c, 20001)
        steps = np.diff(np.asarray(_law(e, grid, np.zeros_like(grid))))
        assert steps.min() >= -1e-14 * np.abs(F).max()  # rounding on the flat interval
        # With a clearance the point (0, 0) sits in the gap, where the slope is 0.
        s, slope = (s, slopes) if c == 0.0 else (s[X != 0.0], slopes[X != 0.0])
        k = jax.jit(jax.vmap(jax.grad(lambda a: _law(e, a[None], jnp.zeros(1))[0])))(s)
        np.testing.assert_allclose(k, slope, rtol=1e-12, atol=1e-9 * np.abs(slopes).max())
        h = 1e-8
        left = (_law(e, s, 0 * s) - _law(e, s - h, 0 * s)) / h
        right = (_law(e, s + h, 0 * s) - _law(e, s, 0 * s)) / h
        np.testing.assert_allclose(left, right, atol=1e-5 * np.abs(slopes).max())


def test_clearance_gives_no_force_inside_the_gap():
    e = _kind_params(clearance=CLEARANCE)
    s = np.linspace(-CLEARANCE, CLEARANCE, 101)
    assert np.all(np.asarray(_law(e, s, np.zeros_like(s))) == 0.0)
    assert np.all(np.asarray(_potential(e, s)) == 0.0)
    # Past the gap the table starts from (0, 0): the force is continuous at its edges.
    f = np.asarray(_law(e, np.array([-CLEARANCE - 1e-9, CLEARANCE + 1e-9]), np.zeros(2)))
    assert np.abs(f).max() < 1e-9 * np.abs(pchip.monotone_slopes(X, F)).max()


def test_force_is_the_derivative_of_the_potential_and_damping_adds():
    e = _kind_params(clearance=CLEARANCE, damping=800.0)
    s = np.linspace(-0.06, 0.06, 241)
    dv = jax.jit(jax.vmap(jax.grad(lambda a: _potential(e, a[None])[0])))(s)
    np.testing.assert_allclose(dv, _law(e, s, np.zeros_like(s)), rtol=1e-12,
                               atol=1e-9 * np.abs(F).max())
    np.testing.assert_allclose(_law(e, s, np.full_like(s, 0.1)) - _law(e, s, 0 * s),
                               800.0 * 0.1, rtol=1e-12)


def test_gradient_in_the_table_forces_matches_finite_differences():
    """dF/d(table forces) at several s (inside, between points, beyond both ends, with
    a padded table beside) by reverse AD against central differences (slopes fixed)."""
    e = _kind_params(clearance=CLEARANCE)
    s = np.array([-0.07, -0.031, -0.012, 0.0103, 0.021, 0.033, 0.09])
    direction = RNG.normal(size=e.force.shape) * 1e3

    def total(force):
        return jnp.sum(jnp.sin(_law(eqx.tree_at(lambda p: p.force, e, force), s,
                                    jnp.zeros_like(s)) / 1e4))

    grad = np.asarray(jax.jit(jax.grad(total))(e.force))
    h = 1e-3
    fd = (total(e.force + h * direction) - total(e.force - h * direction)) / (2 * h)
    np.testing.assert_allclose(np.sum(grad * direction), fd, rtol=1e-7)


def _body_state(z, zdot):
    q = np.array([0, 0, z, 1, 0, 0, 0], dtype=float)
    qdot = np.array([0, 0, zdot, 0, 0, 0, 0], dtype=float)
    return q, qdot


def test_spring_mass_on_a_table_spring_keeps_its_energy():
    """A 200 kg body on a table spring with clearance and a padded second element
    (a softer table, both to the ground along z), no gravity: thrown through the gap
    into both sides of the tables for 1 s, T + V stays within 1e-6 of its start."""
    soft = mb.TableSpring("ground", "mass", (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 2.0),
                          displacements=(-0.02, 0.0, 0.04), forces=(-2e3, 0.0, 3e3))
    system, params = mb.build_system(
        [mb.RigidBody("mass", 200.0, (1.0, 1.0, 1.0))],
        forces=[mb.TableSpring("ground", "mass", (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 1),
                               displacements=X, forces=F, clearance=CLEARANCE), soft])
    assert params.forces["table_spring"].force.shape == (2, X.size)  # padded
    q0, qdot0 = _body_state(0.0, 1.5)
    ts = jnp.linspace(0.0, 1.0, 401)

    @jax.jit
    def run(params):
        sol = mb.simulate_system(mb.SystemLoads(system, params), q0, qdot0, ts[-1], dt0=1e-4,
                                 saveat=diffrax.SaveAt(ts=ts), rtol=1e-11, atol=1e-11)
        # sol.ys is a State (q, qdot, ...), or the tuple (q, qdot) before it existed.
        q, qdot = (sol.ys.q, sol.ys.qdot) if hasattr(sol.ys, "q") else sol.ys[:2]
        energy = jax.vmap(lambda a, b: mb.kinetic_energy(system, params, a, b)
                          + mb.potential_energy(system, params, a))(q, qdot)
        return q[:, 2], energy

    z, energy = (np.asarray(a) for a in run(params))
    assert z.max() > 0.02 and z.min() < -0.02  # through the gap, into both tables
    drift = np.abs(energy - energy[0]).max() / energy[0]
    assert drift < 1e-6, drift


@pytest.mark.parametrize("change, message", [
    (dict(displacements=(0.0, 0.01, 0.01), forces=(0.0, 1e3, 2e3)), "strictly increasing"),
    (dict(displacements=(0.0, 0.02, 0.01)), "strictly increasing"),
    (dict(forces=(0.0, 2e3, 1e3)), "non-decreasing"),
    (dict(forces=(0.0, 1e3)), "equal length"),
    (dict(forces=(np.nan, 1e3, 2e3)), "finite"),
    (dict(clearance=0.002, forces=(1e2, 1e3, 2e3)), r"\(0, 0\)"),
    (dict(clearance=-0.001), "clearance"),
    (dict(axis_i=(0, 0, 0)), "axis_i"),
])
def test_bad_tables_raise_value_error_naming_the_element(change, message):
    spec = dict(displacements=(0.0, 0.01, 0.02), forces=(0.0, 1e3, 2e3), axis_i=(0, 0, 1))
    spec.update(change)
    good = mb.TableSpring("ground", "mass", (0, 0, 0), (0, 0, 0), axis_i=(0, 0, 1),
                          displacements=(0.0, 0.01), forces=(0.0, 1.0), name="left stop")
    bad = mb.TableSpring("ground", "mass", (0, 0, 0), (0, 0, 0), name="right stop", **spec)
    with pytest.raises(ValueError, match=f"'right stop'.*{message}"):
        mb.build_system([mb.RigidBody("mass", 1.0, (1.0, 1.0, 1.0))], forces=[good, bad])
