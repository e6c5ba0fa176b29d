"""Profile measures: UIC60 top, gauge point and rail position; wheel flange measures."""

import functools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.profiles._base import Profile
from jaxrail.profiles.measures import (flange_angle, flange_height, flange_qr, flange_thickness,
                                       gauge_point, highest_point, rail_offset)
from jaxrail.profiles.s1002 import S1002
from jaxrail.profiles.uic60 import uic60

MM = 1e-3
KEYS = ("1:40", "1:20")  # the uncanted head is covered by test_uic60.py
RAILS = tuple(uic60(key) for key in KEYS)
THETAS = (math.atan(1 / 40), math.atan(1 / 20))

# Reference table (profiles.md 2.1), mm: R80 and R13 centres of the uncanted field side.
C80 = np.array([7.50053, -80.12790])
C13 = np.array([23.01603, -14.94915])


# --- rail ---------------------------------------------------------------------------------
#
# One compiled function evaluates all three rails: for each, a vmapped batch of inputs
# x = (inclination, gauge_height, gauge) (the base row, then +-step in each input for
# central differences), giving the values (y_top, z_top, offset) and their reverse-mode
# Jacobian (jax.vjp) at every row.

STEPS = np.array([1e-6, 1e-6, 1e-6])


def _rail_values(rail, x):
    r = eqx.tree_at(lambda q: q.inclination, rail, x[0])
    y_top, z_top = highest_point(r)
    return jnp.stack([y_top, z_top, rail_offset(r, gauge=x[2], gauge_height=x[1])])


def _values_and_jacobian(f, x):
    values, vjp = jax.vjp(f, x)
    (jac,) = jax.vmap(vjp)(jnp.eye(values.shape[0], dtype=values.dtype))
    return values, jac


@jax.jit
def _rail_eval(rails, xs):
    return [jax.vmap(lambda x, rail=rail: _values_and_jacobian(
        lambda v: _rail_values(rail, v), x))(rows) for rail, rows in zip(rails, xs)]


def _rows(base, steps):
    rows = [base]
    for i, h in enumerate(steps):
        for sign in (1.0, -1.0):
            row = np.array(base, dtype=np.float64)
            row[i] += sign * h
            rows.append(row)
    return np.array(rows)


def _central_differences(values, steps):
    return np.stack([(values[1 + 2 * i] - values[2 + 2 * i]) / (2 * h)
                     for i, h in enumerate(steps)], axis=-1)


@functools.cache
def base():
    """{key: values, Jacobian and their central-difference rows} of each rail, evaluated
    once, when a test first asks (not while pytest collects the module)."""
    xs = np.stack([_rows([float(r.inclination), 0.014, 1.435], STEPS) for r in RAILS])
    return {key: dict(values=np.asarray(values[0]), jac=np.asarray(jac[0]),
                      rows=np.asarray(values), jac_rows=np.asarray(jac))
            for key, (values, jac) in zip(KEYS, _rail_eval(RAILS, jnp.asarray(xs)))}


def _rotated(theta, p):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([c * p[0] - s * p[1], s * p[0] + c * p[1]])


def test_highest_points_against_reference():
    y_top = {k: base()[k]["values"][0] / MM for k in KEYS}
    z_top = {k: base()[k]["values"][1] / MM for k in KEYS}
    t40, t20 = math.atan(1 / 40), math.atan(1 / 20)
    # 1:40: on the R300 crown, at 300 sin(theta) on the field side (7.498 mm).
    assert y_top["1:40"] == pytest.approx(300.0 * math.sin(t40), abs=1e-9)
    assert y_top["1:40"] == pytest.approx(7.498, abs=5e-4)
    assert z_top["1:40"] == pytest.approx(300.0 * (1.0 - math.cos(t40)), abs=1e-9)
    # 1:20: on the field-side R80 arc, above its canted centre (11.49 mm).
    c80 = _rotated(t20, C80)
    assert y_top["1:20"] == pytest.approx(c80[0], abs=1e-4)
    assert z_top["1:20"] == pytest.approx(c80[1] + 80.0, abs=1e-4)
    assert y_top["1:20"] == pytest.approx(11.49, abs=5e-3)


def _gauge_point_expected_mm(theta, z_top_mm):
    """Independent: the gauge point lies on the gauge-side R13 arc (table centre)."""
    c13 = _rotated(theta, C13 * np.array([-1.0, 1.0]))
    y = c13[0] - math.sqrt(13.0**2 - (z_top_mm - 14.0 - c13[1]) ** 2)
    slope = -(y - c13[0]) / math.sqrt(13.0**2 - (y - c13[0]) ** 2)
    return y, slope


def test_rail_positions_against_reference():
    for key, theta in zip(KEYS, THETAS):
        y_top, z_top, offset = base()[key]["values"] / MM
        y_gauge, _ = _gauge_point_expected_mm(theta, z_top)
        assert offset == pytest.approx(717.5 - y_gauge, abs=2e-4), key
    # Highest point from the track centre (reference 2.1, CONTACT agrees for 1:40).
    top = {k: (base()[k]["values"][2] + base()[k]["values"][0]) / MM for k in KEYS}
    assert top["1:40"] == pytest.approx(760.53, abs=0.01)
    assert top["1:20"] == pytest.approx(764.00, abs=0.01)


def test_rail_measures_gradients_against_finite_differences():
    for key, theta in zip(KEYS, THETAS):
        jac = base()[key]["jac"]  # rows: y_top, z_top, offset; columns: theta, gh, gauge
        assert np.all(np.isfinite(base()[key]["jac_rows"])), key
        fd = _central_differences(base()[key]["rows"], STEPS)
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-9, err_msg=key)
        # Analytic: d offset/d gauge = 1/2; d offset/d gauge_height = 1/h'(y_gauge).
        assert jac[2, 2] == pytest.approx(0.5, rel=1e-12)
        _, slope = _gauge_point_expected_mm(theta, base()[key]["values"][1] / MM)
        assert jac[2, 1] == pytest.approx(1.0 / slope, rel=1e-4), key
        assert jac[0, 1] == 0.0 and jac[0, 2] == 0.0  # the top ignores the gauge
    # Analytic top derivative: d(300 sin theta)/d theta on the crown (1:40), R80 (1:20).
    t40, t20 = math.atan(1 / 40), math.atan(1 / 20)
    assert base()["1:40"]["jac"][0, 0] == pytest.approx(0.3 * math.cos(t40), rel=1e-9)
    c80_rate = -C80[0] * math.sin(t20) - C80[1] * math.cos(t20)
    assert base()["1:20"]["jac"][0, 0] / MM == pytest.approx(c80_rate, rel=1e-5)


_gauge_point = jax.jit(gauge_point)


def test_gauge_point_and_its_domain_check():
    rail = RAILS[0]
    y_top, z_top, offset = base()["1:40"]["values"]
    y_gauge = float(_gauge_point(rail, 0.014))
    assert y_gauge == pytest.approx(0.7175 - offset, abs=1e-15)
    y_expect, _ = _gauge_point_expected_mm(math.atan(1 / 40), z_top / MM)
    assert y_gauge / MM == pytest.approx(y_expect, abs=2e-4)
    with pytest.raises(Exception, match="gauge depth"):
        jax.block_until_ready(_gauge_point(rail, 0.030))


# --- wheel --------------------------------------------------------------------------------

class FlankWheel(Profile):
    """A wheel-like test profile with known flange geometry (all lengths m):

    flange tip: upper circle, centre (tip_y, tip_z), radius tip_radius; flank: straight
    line at angle ``flank_angle`` tangent to the tip circle; throat: lower circle of
    radius ``throat_radius`` tangent to the flank and to a flat tread ``height = 0``.
    """

    flank_angle: jax.Array
    tip_y: jax.Array
    tip_z: jax.Array
    tip_radius: float = 0.012
    throat_radius: float = 0.013

    def __init__(self, flank_angle, tip_y, tip_z):
        self.flank_angle = jnp.asarray(flank_angle, dtype=jnp.float64)
        self.tip_y = jnp.asarray(tip_y, dtype=jnp.float64)
        self.tip_z = jnp.asarray(tip_z, dtype=jnp.float64)

    @property
    def domain(self):
        return (-0.065, 0.030)

    def geometry(self):
        a, rt, rh = self.flank_angle, self.tip_radius, self.throat_radius
        y1 = self.tip_y + rt * jnp.sin(a)  # tip/flank tangency
        z1 = self.tip_z + rt * jnp.cos(a)
        y2 = y1 + (z1 - rh * (1.0 - jnp.cos(a))) / jnp.tan(a)  # flank/throat tangency
        c2 = y2 + rh * jnp.sin(a)  # throat centre y (tangent to the tread at c2)
        return y1, z1, y2, c2

    def height(self, y):
        y = jnp.asarray(y, dtype=jnp.float64)
        a, rt, rh = self.flank_angle, self.tip_radius, self.throat_radius
        y1, z1, y2, c2 = self.geometry()

        def safe_sqrt(x):
            ok = x > 0.0
            return jnp.where(ok, jnp.sqrt(jnp.where(ok, x, 1.0)), 0.0)

        tip = self.tip_z + safe_sqrt(rt**2 - (y - self.tip_y) ** 2)
        flank = z1 - jnp.tan(a) * (y - y1)
        throat = rh - safe_sqrt(rh**2 - (y - c2) ** 2)
        return jnp.where(y <= y1, tip, jnp.where(y <= y2, flank, jnp.where(y <= c2, throat, 0.0)))


WHEEL_P = np.array([math.radians(70.0), -0.055, 0.016])  # angle, tip_y, tip_z
WHEEL_STEPS = np.array([1e-6, 1e-7, 1e-7])


def _wheel_values(p):
    wheel = FlankWheel(*p)
    return jnp.stack([flange_height(wheel), flange_thickness(wheel), flange_angle(wheel),
                      flange_qr(wheel)])


@jax.jit
def _wheel_eval(ps):
    """Measures (height, Sd, angle, qR) and their reverse-mode Jacobians, vmapped over
    a batch of wheel parameter rows (B, 3)."""
    return jax.vmap(lambda p: _values_and_jacobian(_wheel_values, p))(ps)


def _wheel_analytic(p):
    a, tip_y, tip_z = p
    rt = 0.012
    y1, z1 = tip_y + rt * math.sin(a), tip_z + rt * math.cos(a)
    y10 = y1 + (z1 - 0.010) / math.tan(a)
    y_high = tip_y + math.sqrt(rt**2 - (rt - 0.002) ** 2)
    return np.array([tip_z + rt, y10 + 0.070, a, y10 - y_high])


def test_wheel_measures_values_gradients_and_vmap():
    rows = _rows(WHEEL_P, WHEEL_STEPS)  # the base wheel, then +-step in each parameter
    values, jac = (np.asarray(v) for v in _wheel_eval(jnp.asarray(rows)))
    for row, v in zip(rows, values):
        np.testing.assert_allclose(v, _wheel_analytic(row), rtol=0, atol=1e-12)
    assert values[0, 0] / MM == pytest.approx(28.0, abs=1e-9)
    assert math.degrees(values[0, 2]) == pytest.approx(70.0, abs=1e-9)
    assert np.all(np.isfinite(jac))
    np.testing.assert_allclose(jac[0], _central_differences(values, WHEEL_STEPS),
                               rtol=1e-6, atol=1e-7)
    # Analytic entries: d angle/d angle = 1, d height/d tip_z = 1, d Sd/d tip_y = 1.
    assert jac[0, 2, 0] == pytest.approx(1.0, rel=1e-12)
    assert jac[0, 0, 2] == pytest.approx(1.0, rel=1e-12)
    assert jac[0, 1, 1] == pytest.approx(1.0, rel=1e-9)


def test_wheel_measures_need_the_taping_line_in_the_domain():
    class Shifted(FlankWheel):
        @property
        def domain(self):
            return (-0.065, -0.001)

    with pytest.raises(ValueError, match="taping line"):
        flange_height(Shifted(*WHEEL_P))


def test_s1002_flange_measures():
    fh, sd, angle, qr = (float(v) for v in jax.jit(
        lambda w: jnp.stack([flange_height(w), flange_thickness(w), flange_angle(w),
                             flange_qr(w)]))(S1002()))
    assert fh / MM == pytest.approx(28.0, abs=1e-6)
    assert sd / MM == pytest.approx(32.5, abs=1e-4)  # F = 10 at S = -37.5 (reference 1.2)
    assert math.degrees(angle) == pytest.approx(math.degrees(math.atan(2.747477419)), abs=1e-6)
    assert math.degrees(angle) == pytest.approx(70.0, abs=1e-5)
    # qR from the section formulas: F = 26 on section F (R20) and F = 10 on section D (R13).
    s26 = -58.558326413 + math.sqrt(20.0**2 - (26.0 - 8.834924130) ** 2)
    s10 = -26.210665 - math.sqrt(13.0**2 - (16.446 - 10.0) ** 2)
    assert -49.662510381 < s26 < -39.764473993 and -38.426669071 < s10 < -35.0
    assert qr / MM == pytest.approx(s10 - s26, abs=1e-4)
    assert qr / MM == pytest.approx(10.79, abs=0.01)
