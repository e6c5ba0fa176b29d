"""Polach creep forces: limits, saturation, signs, 2005 extension, edge cases, AD."""

import itertools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.kalker import kalker_coefficients
from jaxrail.contact.polach import PolachParameters, polach

# A typical tread contact: 80 kN, a = 6 mm, b = 4 mm, steel.
Q, MU, A, B, G, NU = 8.0e4, 0.4, 6.0e-3, 4.0e-3, 8.2e10, 0.28
C11, C22, C23 = (float(c) for c in kalker_coefficients(A / B, NU))


def _forces(p):
    """p = (Q, mu, a, b, xi, eta, phi) -> (fx, fy)."""
    return jnp.stack(polach(p[0], p[1], p[2], p[3], p[4], p[5], p[6], G, NU))


def _forces_2005(p, k_a, k_s, a_ratio, b_rate, speed):
    # Fixed Kalker coefficients (those of A/B): the 2005 tests need not recompile the
    # coefficient interpolation, which the 1999 tests cover.
    params = PolachParameters(k_A=k_a, k_S=k_s, A_ratio=a_ratio, B=b_rate)
    kw = {"parameters": params, "rolling_speed": speed, "coefficients": (C11, C22, C23)}
    return jnp.stack(polach(p[0], p[1], p[2], p[3], p[4], p[5], p[6], G, NU, **kw))


N_PAD = 48  # all batches are padded to this many contacts: one compilation per function
_PAD_ROW = np.array([Q, MU, A, B, 1e-3, 0.0, 0.0])

_forces_jit = jax.jit(jax.vmap(_forces))  # over contacts: (n, 7) -> (n, 2)
_forces_2005_jit = jax.jit(jax.vmap(_forces_2005, (0, None, None, None, None, None)))
_jac_jit = jax.jit(jax.vmap(jax.jacrev(_forces)))  # (n, 2, 7), reverse mode
_jac_2005_jit = jax.jit(jax.vmap(jax.jacrev(_forces_2005), (0, None, None, None, None, None)))


def _padded(fun):
    def run(p, *args):
        p = np.atleast_2d(np.asarray(p, dtype=float))
        n = p.shape[0]
        assert n <= N_PAD
        full = np.concatenate([p, np.broadcast_to(_PAD_ROW, (N_PAD - n, 7))])
        return np.array(fun(full, *(float(a) for a in args)))[:n]

    return run


forces = _padded(_forces_jit)
forces_2005 = _padded(_forces_2005_jit)
jac_rev = _padded(_jac_jit)
jac_rev_2005 = _padded(_jac_2005_jit)


def contacts(creepages, q=Q, mu=MU, a=A, b=B):
    """(n, 7) parameter rows for creepage triples (xi, eta, phi)."""
    c = np.atleast_2d(np.asarray(creepages, dtype=float))
    head = np.broadcast_to([q, mu, a, b], (c.shape[0], 4))
    return np.concatenate([head, c], axis=1)


def reference_polach(q, mu, a, b, sx, sy, psi, c11, c22, c23):
    """Direct NumPy transcription of reference/contact-mechanics.md 4.2 (Polach 1999),
    including the K_M, delta chain as printed. Needs s > 0 and s_C > 0."""
    syc = sy + psi * a if abs(sy + psi * a) > abs(sy) else sy
    sc = math.hypot(sx, syc)
    s = math.hypot(sx, sy)
    cjj = math.sqrt((c11 * sx / s) ** 2 + (c22 * sy / s) ** 2)
    c_stiff = 3.0 / 8.0 * G / a * cjj
    eps = 2.0 / 3.0 * c_stiff * math.pi * a * a * b / (q * mu) * sc
    f = 2.0 * q * mu / math.pi * (eps / (1 + eps**2) + math.atan(eps))
    ks = 1 + 6.3 * (1 - math.exp(-a / b))
    eps_psi = 8.0 / 3.0 * G * b * math.sqrt(a * b) * c23 * abs(syc) / (q * mu * ks)
    d = (eps_psi**2 - 1) / (eps_psi**2 + 1)
    k_m = abs(eps_psi) * (d**3 / 3 - d**2 / 2 + 1 / 6) - math.sqrt((1 - d**2) ** 3) / 3
    fys = -9.0 / 16.0 * a * q * mu * abs(k_m) * ks * psi / sc
    return -f * sx / sc, -f * sy / sc + fys


def test_matches_transcription_of_the_reference():
    rng = np.random.default_rng(1)
    rows = []
    for _ in range(40):
        sx, sy = rng.normal(0.0, 4e-3, 2)
        psi = rng.normal(0.0, 1.5)
        rows.append((sx, sy, psi))
    # include spin opposing the lateral creepage on both sides of Polach's switch
    rows += [(1e-3, -2e-3, 0.5), (1e-3, -2e-3, 0.9), (-2e-4, 1e-3, -0.2), (0.0, 1e-3, -0.5)]
    ours = np.array(forces(contacts(rows)))
    ref = np.array([reference_polach(Q, MU, A, B, *r, C11, C22, C23) for r in rows])
    np.testing.assert_allclose(ours, ref, rtol=1e-11, atol=1e-9)


def test_linear_limits():
    tiny = 1e-9
    fx, fy = np.array(forces(contacts([(tiny, 0, 0), (0, tiny, 0), (0, 0, tiny)]))).T
    # Kalker's linear theory, Fx = -G a b c11 xi, Fy = -G a b c22 eta
    assert fx[0] == pytest.approx(-G * A * B * C11 * tiny, rel=1e-6)
    assert fy[1] == pytest.approx(-G * A * B * C22 * tiny, rel=1e-6)
    assert fy[0] == 0.0 and fx[1] == 0.0
    # pure spin: Fy = -G (ab)^1.5 c23 phi (relative error 2 eps_psi^2, ~1e-16 here)
    assert fy[2] == pytest.approx(-G * (A * B) ** 1.5 * C23 * tiny, rel=1e-6)
    assert fx[2] == 0.0


def test_spin_limit_accuracy_at_small_but_finite_spin():
    # Relative deviation from the linear spin law is 2 eps_psi^2: check 1e-3 accuracy
    # at a spin where eps_psi ~ 0.02, and the predicted deviation itself.
    psi = 0.05
    ks = 1 + 6.3 * (1 - math.exp(-A / B))
    eps_psi = 8 / 3 * G * B * math.sqrt(A * B) * C23 * abs(psi * A) / (Q * MU * ks)
    fy = float(forces(contacts([(0, 0, psi)]))[0, 1])
    linear = -G * (A * B) ** 1.5 * C23 * psi
    assert abs(fy / linear - 1) < 1e-3
    assert fy / linear == pytest.approx(1 / (1 + eps_psi**2) ** 2, rel=1e-12)


def test_saturation_at_mu_q():
    big = [(0.5, 0, 0), (0, -0.5, 0), (0.3, 0.4, 0), (-0.3, 0.4, 2.0), (0.2, -0.1, -3.0)]
    f = forces(contacts(big))
    mag = np.hypot(f[:, 0], f[:, 1])
    np.testing.assert_allclose(mag[:3], MU * Q, rtol=1e-6)
    # with spin Polach's creep part saturates at mu Q s / s_C (s_C includes phi a); the
    # spin part decays as 1/eps_psi^4 and is ~0.5 % of the total here
    for (xi, eta, phi), m in zip(big[3:], mag[3:]):
        eta_c = eta + phi * A if abs(eta + phi * A) > abs(eta) else eta
        expected = MU * Q * math.hypot(xi, eta) / math.hypot(xi, eta_c)
        assert m == pytest.approx(expected, rel=1e-2) and m < MU * Q
    # the force grows monotonically towards mu Q along a ray
    s = np.geomspace(1e-6, 1.0, 40)
    f_ray = forces(contacts(np.stack([0.6 * s, 0.8 * s, 0 * s], 1)))
    mag = np.hypot(f_ray[:, 0], f_ray[:, 1])
    assert np.all(np.diff(mag) > 0) and mag[-1] < MU * Q


def test_force_opposes_creepage_for_all_sign_combinations():
    mags = (2e-3, 1.5e-3, 0.4)  # xi, eta [-], phi [1/m]
    rows = [
        (sx * mags[0], sy * mags[1], sp * mags[2])
        for sx, sy, sp in itertools.product((-1, 1), (-1, 0, 1), (-1, 0, 1))
    ]
    f = np.array(forces(contacts(rows)))
    for (xi, eta, phi), (fx, fy) in zip(rows, f):
        assert fx * xi < 0
        if eta != 0 and (phi == 0 or np.sign(phi) == np.sign(eta)):
            assert fy * eta < 0
        if eta == 0 and phi != 0:
            assert fy * phi < 0
        if eta == 0 and phi == 0:
            assert fy == 0
    # odd symmetry and lateral mirror symmetry
    rows = np.array(rows)
    flipped = np.array(forces(contacts(-rows)))
    np.testing.assert_allclose(flipped, -f, rtol=1e-13, atol=1e-12)
    mirrored = np.array(forces(contacts(rows * [1, -1, -1])))
    np.testing.assert_allclose(mirrored, f * [1, -1], rtol=1e-13, atol=1e-12)


def test_spin_rule_is_continuous_with_a_kink():
    # Polach's switch of s_yC happens at eta = -phi a / 2: the force is continuous there
    # (the jump over 2d is what the slope G a b c22 predicts, nothing more)...
    phi = 0.5
    eta0 = -phi * A / 2
    d = 1e-12
    f = forces(contacts([(1e-4, eta0 - d, phi), (1e-4, eta0 + d, phi)]))
    assert np.all(np.abs(f[1] - f[0]) < 2 * G * A * B * C22 * 2 * d)
    # ...but with a kink: the slope d fy / d eta differs on the two sides
    h = 1e-7
    jl = jac_rev(contacts([(1e-4, eta0 - h, phi)]))[0, 1, 5]
    jr = jac_rev(contacts([(1e-4, eta0 + h, phi)]))[0, 1, 5]
    assert abs(jl - jr) > 1e-2 * abs(jl)


def test_2005_defaults_reduce_to_1999():
    rng = np.random.default_rng(2)
    rows = np.column_stack([rng.normal(0, 3e-3, (20, 2)), rng.normal(0, 1, 20)])
    rows[0] = 0.0
    p = contacts(rows)
    f99 = np.array(forces(p))
    np.testing.assert_allclose(np.array(forces_2005(p, 1.0, 1.0, 1.0, 0.0, 0.0)), f99, rtol=1e-14, atol=1e-12)
    # A = 1 makes the friction constant whatever B and V are
    f_a1 = forces_2005(p, 1.0, 1.0, 1.0, 0.6, 30.0)
    np.testing.assert_allclose(f_a1, f99, rtol=1e-14, atol=1e-12)
    f_default = polach(Q, MU, A, B, *rows[1], G, NU, parameters=PolachParameters(), rolling_speed=20.0)
    np.testing.assert_allclose(np.array(f_default), f99[1], rtol=1e-13)


def test_2005_reduction_factors_set_initial_slope():
    tiny = 1e-9
    k_a, k_s = 0.3, 0.75
    f = np.array(forces_2005(contacts([(tiny, 0, 0)]), k_a, k_s, 1.0, 0.0, 20.0))
    # F = (2 Q mu / pi) (k_A eps + k_S eps) at small eps: slope G a b c11 (k_A + k_S) / 2
    assert f[0, 0] == pytest.approx(-G * A * B * C11 * tiny * (k_a + k_s) / 2, rel=1e-6)
    # saturation: F / (mu Q) - 1 -> (2/pi) (1/k_A - 1/k_S) / eps, which is positive for
    # k_A < k_S (the 'wet' set): the force approaches mu Q from above
    for s in (0.5, 50.0):
        eps = math.pi * G * A * B * C11 * s / (4 * Q * MU)
        fx = forces_2005(contacts([(s, 0, 0)]), k_a, k_s, 1.0, 0.0, 20.0)[0, 0]
        assert -fx / (MU * Q) - 1 == pytest.approx(2 / math.pi * (1 / k_a - 1 / k_s) / eps, rel=1e-2)


def test_2005_falling_friction():
    speed, a_ratio, b_rate = 20.0, 0.4, 0.6
    s = np.linspace(1e-4, 0.3, 48)
    rows = contacts(np.column_stack([s, 0 * s, 0 * s]))
    f = -forces_2005(rows, 1.0, 0.4, a_ratio, b_rate, speed)[:, 0]
    peak = np.argmax(f)
    assert 0 < peak < s.size - 1
    assert np.all(np.diff(f[peak + 1 :]) < 0)  # decreasing beyond the adhesion peak
    # the force follows mu(w) Q at large slip: mu = mu0 [(1 - A) exp(-B w) + A]
    mu_w = MU * ((1 - a_ratio) * np.exp(-b_rate * s[-1] * speed) + a_ratio)
    assert f[-1] == pytest.approx(mu_w * Q, rel=2e-2)
    assert f[-1] < 0.7 * f[peak]


def test_zero_load_and_zero_area():
    rows = np.array(
        [
            [0.0, MU, 0.0, 0.0, 1e-3, 1e-3, 0.1],
            [0.0, MU, A, B, 1e-3, 1e-3, 0.1],
            [Q, MU, 0.0, 0.0, 1e-3, 1e-3, 0.1],
            [0.0, MU, 0.0, 0.0, 0.0, 0.0, 0.0],
            [Q, 0.0, A, B, 1e-3, 0.0, 0.0],
        ]
    )
    f = forces(rows)
    assert np.all(f == 0.0)
    assert np.all(np.isfinite(jac_rev(rows)))
    assert np.all(np.isfinite(jac_rev_2005(rows, 0.3, 0.75, 0.4, 0.2, 20.0)))


def test_no_nan_gradients_at_zero_creepage_and_zero_spin():
    rows = contacts(
        [(0, 0, 0), (1e-3, 0, 0), (0, 1e-3, 0), (0, 0, 0.3), (1e-3, -1e-3, 0), (0, -0.3 * A / 2, 0.3)]
    )
    assert np.all(np.isfinite(jac_rev(rows)))
    j2005 = np.array(jac_rev_2005(rows, 0.3, 0.75, 0.4, 0.2, 20.0))
    assert np.all(np.isfinite(j2005))
    # at zero creepage the Jacobian is Kalker's linear law
    j0 = np.array(jac_rev(contacts([(0, 0, 0)])))[0][:, 4:]
    expected = -np.array([[G * A * B * C11, 0, 0], [0, G * A * B * C22, G * (A * B) ** 1.5 * C23]])
    np.testing.assert_allclose(j0, expected, rtol=1e-12, atol=1e-9)


def _central_differences(fun, p, rel=1e-6):
    jac = np.zeros((p.shape[0], 2, p.shape[1]))
    for i in range(p.shape[1]):
        h = rel * np.maximum(np.abs(p[:, i]), 1e-3 if i >= 4 else 1.0)
        e = np.zeros_like(p)
        e[:, i] = h
        jac[:, :, i] = (np.array(fun(p + e)) - np.array(fun(p - e))) / (2 * h[:, None])
    return jac


def test_grad_matches_central_differences():
    rows = contacts([(1e-3, 2e-3, 0.3), (-4e-3, 1e-3, -0.8), (2e-2, -3e-2, 1.0), (1e-3, -1e-3, 2.0)])
    rows[1, 2:4] = [3e-3, 7e-3]  # a/b < 1 as well
    ad = np.array(jac_rev(rows))
    fd = _central_differences(forces, rows)
    scale = np.abs(ad).max(axis=(1, 2), keepdims=True)  # per contact
    np.testing.assert_allclose(ad / scale, fd / scale, rtol=0, atol=1e-6)
    # forward mode agrees (one contact, unbatched)
    fwd = np.array(jax.jit(jax.jacfwd(_forces))(rows[0]))
    np.testing.assert_allclose(fwd, ad[0], rtol=1e-10, atol=1e-6)
    # along the axes at zero creepage (with and without spin) AD equals the one-sided
    # limits that central differences see
    rows0 = contacts([(0, 0, 0), (0, 0, 0.4)])
    ad0 = np.array(jac_rev(rows0))[:, :, 4:]
    fd0 = _central_differences(forces, rows0)[:, :, 4:]
    np.testing.assert_allclose(ad0, fd0, rtol=1e-5, atol=1e-3)

    def f05(p):
        return forces_2005(p, 0.3, 0.75, 0.4, 0.2, 20.0)


    ad05 = np.array(jac_rev_2005(rows, 0.3, 0.75, 0.4, 0.2, 20.0))
    fd05 = _central_differences(f05, rows)
    scale = np.abs(ad05).max(axis=(1, 2), keepdims=True)
    np.testing.assert_allclose(ad05 / scale, fd05 / scale, rtol=0, atol=1e-6)


def test_jit_vmap_and_broadcasting_agree():
    rows = contacts([(1e-3, 2e-3, 0.3), (-4e-3, 1e-3, -0.8), (0, 0, 0)])
    batched = forces(rows)  # jit(vmap)
    fx, fy = jax.jit(polach)(*rows.T, G, NU)  # plain broadcasting over arrays
    np.testing.assert_allclose(np.column_stack([fx, fy]), batched, rtol=1e-13, atol=1e-12)


def test_bad_arguments():
    with pytest.raises(ValueError, match="rolling_speed"):
        polach(Q, MU, A, B, 1e-3, 0.0, 0.0, parameters=PolachParameters())
    with pytest.raises(TypeError, match="parameters"):
        polach(Q, MU, A, B, 1e-3, 0.0, 0.0, parameters={"k_A": 1.0}, rolling_speed=1.0)
    with pytest.raises(ValueError, match="coefficients"):
        polach(Q, MU, A, B, 1e-3, 0.0, 0.0, coefficients=(1.0, 2.0))


def test_parameter_sets():
    dry, wet = PolachParameters.dry(), PolachParameters.wet()
    assert float(dry.k_S) == 0.4 and float(wet.k_A) == 0.3
    assert dry.B.dtype == jnp.float64
    # coefficients override: the linear law follows the given c11
    f = polach(Q, MU, A, B, 1e-9, 0.0, 0.0, coefficients=(5.0, 4.0, 2.0))
    assert float(f[0]) == pytest.approx(-G * A * B * 5.0 * 1e-9, rel=1e-6)


def test_tabulated_kalker_coefficients_match_direct():
    # The default tabulated coefficients (test_kalker_table.py) against the defining
    # evaluation, through the whole force law: tread-like and flange-like ellipses.
    a = np.array([6e-3, 3e-3, 1.5e-3, 8e-3])
    b = np.array([4e-3, 6e-3, 3e-2, 1e-4])
    args = (Q, MU, a, b, 2e-3, -1e-3, 0.5, G, NU)
    table = np.array(jax.jit(lambda: jnp.stack(polach(*args)))())
    direct = np.array(jax.jit(lambda: jnp.stack(polach(*args, kalker_method="direct")))())
    np.testing.assert_allclose(table, direct, rtol=5e-7)
    with pytest.raises(ValueError, match="method"):
        polach(*args, kalker_method="exact")
