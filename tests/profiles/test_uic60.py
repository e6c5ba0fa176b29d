"""UIC60 / 60E1 rail head: geometry against the reference table, cant, smoothness, AD."""

import math
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from jaxrail.profiles.files import read_simpack_points
from jaxrail.profiles.uic60 import UIC60, uic60

MM = 1e-3
DATA = Path(__file__).resolve().parents[1] / "data"

KEYS = ("none", "1:40", "1:20")
RAILS = {key: uic60(key) for key in KEYS}
N = 1024  # every evaluation uses this many points per rail: one compilation per file


def _point_values(rail, y):
    """Height, slope, curvature at y; their derivatives in the inclination; dk/dy."""

    def with_theta(theta):
        r = eqx.tree_at(lambda q: q.inclination, rail, theta)
        return jnp.stack([r.height(y), r.slope(y), r.curvature(y)])

    values, d_theta = jax.jvp(with_theta, (rail.inclination,), (jnp.ones(()),))
    return values, d_theta, jax.grad(rail.curvature)(y)


@jax.jit
def _evaluate_all(rails, ys):
    out = []
    for rail, y in zip(rails, ys):
        values, d_theta, dk_dy = jax.vmap(lambda v, rail=rail: _point_values(rail, v))(y)

        def total_curvature(theta, rail=rail, y=y):
            r = eqx.tree_at(lambda q: q.inclination, rail, theta)
            return jnp.sum(jax.vmap(r.curvature)(y))

        reverse = jax.grad(total_curvature)(rail.inclination)  # reverse mode, summed
        out.append((values, d_theta, dk_dy, reverse))
    return out


def evaluate(points, rails=None):
    """Evaluate each rail at its points: ``points`` maps key -> 1-D array [m] (<= N).

    Returns key -> dict with h, s, d2, k (values), h_t, s_t, k_t (d/d inclination,
    forward mode), k_y (dk/dy), and the reverse- and forward-mode d sum(k)/d inclination
    over the padded batch (k_t_sum_reverse, k_t_sum_padded).
    """
    rails = RAILS if rails is None else rails
    ys = np.zeros((len(KEYS), N))
    for i, key in enumerate(KEYS):
        if key in points:
            y = np.asarray(points[key], dtype=np.float64)
            assert y.ndim == 1 and y.size <= N
            ys[i, : y.size] = y
    out = _evaluate_all(tuple(rails[k] for k in KEYS), jnp.asarray(ys))
    result = {}
    for i, key in enumerate(KEYS):
        if key not in points:
            continue
        n = np.asarray(points[key]).size
        values, d_theta, dk_dy, reverse = (np.asarray(v) for v in out[i])
        h, s, k = values[:n, 0], values[:n, 1], values[:n, 2]
        result[key] = dict(
            h=h, s=s, k=k, d2=k * (1.0 + s * s) ** 1.5,
            h_t=d_theta[:n, 0], s_t=d_theta[:n, 1], k_t=d_theta[:n, 2],
            k_y=dk_dy[:n], k_t_sum_reverse=float(reverse), k_t_sum_padded=float(np.sum(d_theta[:, 2])))
    return result


def shifted_rails(eps):
    return {k: eqx.tree_at(lambda q: q.inclination, r, r.inclination + eps) for k, r in RAILS.items()}


def _independent_head_mm():
    """Uncanted field-side head [mm] from the defining dimensions, solved with scipy."""
    # R80: internally tangent to R300 at the crown point with y = 10.228.
    p1 = np.array([10.228, -300.0 + math.sqrt(300.0**2 - 10.228**2)])
    normal1 = (p1 - np.array([0.0, -300.0])) / 300.0
    c80 = p1 - 80.0 * normal1
    # R13: internally tangent to R80 at y = 26.0265.
    p2 = np.array([26.0265, c80[1] + math.sqrt(80.0**2 - (26.0265 - c80[0]) ** 2)])
    c13 = p2 - 13.0 * (p2 - c80) / 80.0
    # Flank 1:20 (dz/dy = -20): the R13 point of that slope, found by root search.
    def slope_error(y):
        d = y - c13[0]
        return -d / math.sqrt(13.0**2 - d * d) + 20.0

    y3 = brentq(slope_error, c13[0], c13[0] + 13.0 - 1e-9, xtol=1e-14)
    p3 = np.array([y3, c13[1] + math.sqrt(13.0**2 - (y3 - c13[0]) ** 2)])
    return dict(p1=p1, p2=p2, p3=p3, c80=c80, c13=c13)


HEAD = _independent_head_mm()


def _canted(theta, y_mm, z_mm):
    """Rotate uncanted points [mm] toward the track centre (gauge side is -y)."""
    c, s = math.cos(theta), math.sin(theta)
    return c * y_mm - s * z_mm, s * y_mm + c * z_mm


def _uncanted_height_mm(y):
    """Independent numpy evaluation of the uncanted head [mm] (|y| <= p3)."""
    a = np.abs(y)
    c80, c13 = HEAD["c80"], HEAD["c13"]
    crown = -300.0 + np.sqrt(300.0**2 - a**2)
    side = c80[1] + np.sqrt(np.clip(80.0**2 - (a - c80[0]) ** 2, 0, None))
    corner = c13[1] + np.sqrt(np.clip(13.0**2 - (a - c13[0]) ** 2, 0, None))
    return np.where(a <= HEAD["p1"][0], crown, np.where(a <= HEAD["p2"][0], side, corner))


def test_independent_geometry_matches_reference_table():
    # The reference table (mm, rounded to the digits given there).
    np.testing.assert_allclose(HEAD["p1"], [10.228, -0.17440], atol=1e-5)
    np.testing.assert_allclose(HEAD["p2"], [26.0265, -2.30252], atol=1e-5)
    np.testing.assert_allclose(HEAD["p3"], [35.99981, -14.29996], atol=1e-5)
    np.testing.assert_allclose(HEAD["c80"], [7.50053, -80.12790], atol=1e-5)
    np.testing.assert_allclose(HEAD["c13"], [23.01603, -14.94915], atol=1e-5)


def test_uncanted_joints_and_head_width():
    rail = RAILS["none"]
    jy, jz = (np.asarray(v) / MM for v in rail.joints())
    expect = [HEAD["p3"], HEAD["p2"], HEAD["p1"]]
    for k, p in enumerate(expect):
        np.testing.assert_allclose([jy[k], jz[k]], [-p[0], p[1]], atol=1e-4)  # gauge side
        np.testing.assert_allclose([jy[5 - k], jz[5 - k]], [p[0], p[1]], atol=1e-4)
    assert jy[5] - jy[0] == pytest.approx(71.99962, abs=1e-4)  # head width 72.00 mm
    assert round(jy[5] - jy[0], 2) == 72.00
    # The profile passes through the inner joints (the R13/flank joints lie just
    # outside the uncanted domain, which ends at 87 degrees)...
    r = evaluate({"none": jy[1:5] * MM})["none"]
    np.testing.assert_allclose(r["h"] / MM, jz[1:5], atol=1e-9)
    # ...and the R13 arcs meet the flanks with the 1:20 flank slope.
    for k, piece in ((0, 0), (0, 1), (5, 5), (5, 6)):
        _, slope = rail.piece_height_slope(jy[k] * MM, piece)
        assert float(slope) == pytest.approx(20.0 if k == 0 else -20.0, rel=1e-6)


def test_uncanted_height_against_independent_formula():
    y_mm = np.linspace(-35.9, 35.9, 1001)
    r = evaluate({"none": y_mm * MM})["none"]
    np.testing.assert_allclose(r["h"] / MM, _uncanted_height_mm(y_mm), atol=1e-9)


def test_canted_profiles_are_the_rotated_head():
    y0 = np.linspace(-35.9, 35.99, 1001)
    points, expected = {}, {}
    for key, slope in (("1:40", 1 / 40), ("1:20", 1 / 20)):
        lo, hi = RAILS[key].domain
        y1, z1 = _canted(math.atan(slope), y0, _uncanted_height_mm(y0))
        inside = (y1 * MM > lo) & (y1 * MM < hi)
        assert inside.sum() > 900
        points[key], expected[key] = y1[inside] * MM, z1[inside]
    result = evaluate(points)
    for key in points:
        np.testing.assert_allclose(result[key]["h"] / MM, expected[key], atol=1e-9)


@pytest.mark.parametrize("key", KEYS)
def test_joints_are_continuous_in_height_and_slope(key):
    rail = RAILS[key]
    lo, hi = rail.domain
    jy, jz = rail.joints()
    for k in range(6):
        # Joint k separates piece k (gauge side) and piece k + 1.
        h_left, s_left = rail.piece_height_slope(jy[k], k)
        h_right, s_right = rail.piece_height_slope(jy[k], k + 1)
        if lo <= float(jy[k]) <= hi:
            assert abs(float(h_left - jz[k])) < 1e-12  # m
            assert abs(float(h_right - jz[k])) < 1e-12
            assert abs(float(s_left - s_right)) < 1e-9 * max(1.0, abs(float(s_left)))
        else:  # R13/flank joints beyond an end; at 1:20 the gauge one is vertical
            assert abs(float(h_left - h_right)) < 1e-9
    assert sum(lo <= float(v) <= hi for v in jy) == (4 if key == "none" else 5)


def _domain_points(rail, n=N - 8):
    lo, hi = rail.domain
    ys = np.concatenate([np.linspace(lo, hi, n), np.asarray(rail.joints()[0]), [lo, hi]])
    return np.sort(ys[(ys >= lo) & (ys <= hi)])


def test_convex_graph_without_nan_over_domain():
    points = {key: _domain_points(RAILS[key]) for key in KEYS}
    result = evaluate(points)
    for key in KEYS:
        r = result[key]
        for name in ("h", "s", "k", "h_t", "s_t", "k_t", "k_y"):
            assert np.all(np.isfinite(r[name])), (key, name)
        assert np.max(r["d2"]) <= 1e-9, key  # z'' <= 0: convex head
        assert np.all(np.diff(r["s"]) <= 1e-9), key  # the slope never increases
        # The domain stops before a vertical tangent (87 degrees at most).
        assert np.max(np.abs(r["s"])) <= math.tan(math.radians(87.0)) * (1 + 1e-9), key
        # ...and reaches past the gauge point (14 mm below the top) on both sides.
        z_top = np.max(r["h"])
        assert z_top - r["h"][0] > 14.2 * MM and z_top - r["h"][-1] > 14.2 * MM, key


def test_inclination_zero_is_mirror_symmetric():
    rail = RAILS["none"]
    lo, hi = rail.domain
    assert lo == pytest.approx(-hi, abs=1e-15)
    ys = np.linspace(0.0, hi, 501)
    pos = evaluate({"none": ys})["none"]
    neg = evaluate({"none": -ys})["none"]
    np.testing.assert_allclose(pos["h"], neg["h"], atol=1e-15)
    np.testing.assert_allclose(pos["s"], -neg["s"], atol=1e-12)
    np.testing.assert_allclose(pos["d2"], neg["d2"], rtol=1e-9)


def test_canted_highest_point_is_on_the_field_side():
    # Brute force: coarse over the domain, then a 1 micron grid around the coarse max.
    # (The measures module refines this further; see test_measures.py.)
    coarse = {key: np.linspace(*RAILS[key].domain, N) for key in KEYS}
    result = evaluate(coarse)
    fine = {key: coarse[key][np.argmax(result[key]["h"])] + np.arange(-500, 500) * 1e-6
            for key in KEYS}
    result = evaluate(fine)
    top = {key: fine[key][np.argmax(result[key]["h"])] / MM for key in KEYS}
    assert top["none"] == pytest.approx(0.0, abs=1e-3)
    assert top["1:40"] == pytest.approx(300.0 * math.sin(math.atan(1 / 40)), abs=1e-3)
    assert top["1:40"] == pytest.approx(7.498, abs=1.5e-3)
    assert top["1:20"] == pytest.approx(11.49, abs=6e-3)


def test_matches_manchester_benchmark_rail_file():
    """MBench_UIC60_v3.prr is canted 1:40 with its origin at the highest point and
    z down; after aligning the highest points the head agrees to the reference's
    0.02 mm mean / 0.06 mm max normal distance."""
    y_f, z_f, _ = read_simpack_points(DATA / "MBench_UIC60_v3.prr")
    rail = RAILS["1:40"]
    y_top = 0.3 * math.sin(rail.inclination)  # the top lies on the R300 crown
    z_top = 0.3 * (1.0 - math.cos(rail.inclination))
    y, z = y_f + y_top, -z_f + z_top
    lo, hi = rail.domain
    inside = (y > lo) & (y < hi)
    assert inside.sum() > 250
    r = evaluate({"1:40": y[inside]})["1:40"]
    dist = np.abs(z[inside] - r["h"]) / np.sqrt(1.0 + r["s"] ** 2)
    assert dist.mean() < 0.03 * MM
    assert dist.max() < 0.06 * MM


def test_factory_names_and_bad_input():
    assert uic60().name == "UIC60 1:40"
    assert uic60("1:20").name == "UIC60 1:20"
    assert uic60("none").name == uic60("0").name == uic60(0.0).name == "UIC60 no inclination"
    assert float(uic60(1 / 40).inclination) == pytest.approx(0.0249948, abs=1e-7)
    assert float(uic60("1:20").inclination) == pytest.approx(0.0499584, abs=1e-7)
    assert uic60("none").inclination.dtype == jnp.float64
    with pytest.raises(ValueError, match="1:30"):
        uic60("1:30")
    with pytest.raises(ValueError, match="inclination"):
        UIC60(jnp.zeros(2))
    with pytest.raises(ValueError, match="outside"):
        UIC60(0.2)
    with pytest.raises(ValueError, match="domain"):
        jax.jit(lambda a: UIC60(a).height(0.0))(0.01)
    with pytest.raises(ValueError, match="domain"):
        UIC60(0.0, domain=(0.01, 0.02))


# --- jit / vmap / grad against finite differences ----------------------------------------

def _off_joints(rail, ys, gap):
    """Central differences need a smooth neighbourhood: drop points near the joints."""
    jy = np.asarray(rail.joints()[0])
    return ys[np.min(np.abs(ys[:, None] - jy[None, :]), axis=1) > gap]


def test_slope_and_curvature_against_finite_differences():
    eps = 1e-7
    points = {}
    for key in KEYS:
        lo, hi = RAILS[key].domain
        points[key] = _off_joints(RAILS[key], np.linspace(lo + 1e-5, hi - 1e-5, 301), 5e-5)
    mid = evaluate(points)  # d2 here is the curvature times (1 + s^2)^1.5
    plus = evaluate({k: v + eps for k, v in points.items()})
    minus = evaluate({k: v - eps for k, v in points.items()})
    for key in KEYS:
        s_fd = (plus[key]["h"] - minus[key]["h"]) / (2 * eps)
        d2_fd = (plus[key]["s"] - minus[key]["s"]) / (2 * eps)
        r = mid[key]
        np.testing.assert_allclose(r["s"], s_fd, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(r["d2"], d2_fd, rtol=1e-5, atol=1e-3)
        # Every piece is a circle or a line, so the curvature is -1/R (or 0) piecewise
        # and its y-derivative (by AD) vanishes.
        piece = np.searchsorted(np.asarray(RAILS[key].joints()[0]), points[key])
        radius_mm = np.array([np.inf, 13.0, 80.0, 300.0, 80.0, 13.0, np.inf])[piece]
        np.testing.assert_allclose(r["k"], -1.0 / (radius_mm * MM), rtol=1e-9)
        assert np.max(np.abs(r["k_y"])) < 1e-6


def test_derivatives_wrt_inclination_against_finite_differences():
    eps = 1e-6
    points = {key: _off_joints(RAILS[key], np.linspace(*RAILS[key].domain, 301)[1:-1], 2e-4)
              for key in KEYS}
    mid = evaluate(points)
    plus = evaluate(points, shifted_rails(eps))
    minus = evaluate(points, shifted_rails(-eps))
    for key in KEYS:
        r = mid[key]
        for name in ("h", "s", "k"):
            fd = (plus[key][name] - minus[key][name]) / (2 * eps)
            # FD round-off ~ 1e-16 |value| / eps; the curvature of an arc does not
            # change under rotation, so there k_t ~ 0 and only the round-off is left.
            noise = 1e-9 * np.max(np.abs(r[name]))
            np.testing.assert_allclose(r[name + "_t"], fd, rtol=1e-5, atol=noise,
                                       err_msg=f"{key} {name}")
        # Reverse mode (summed over the padded batch) agrees with forward mode.
        assert r["k_t_sum_reverse"] == pytest.approx(r["k_t_sum_padded"], rel=1e-9, abs=1e-9)


def test_negative_inclination_is_the_mirror_image():
    rail, mirrored = uic60(1 / 40), uic60(-1 / 40)
    assert mirrored.domain == pytest.approx((-rail.domain[1], -rail.domain[0]), abs=1e-15)
    ys = jnp.linspace(*rail.domain, 201)
    h = jax.jit(jax.vmap(rail.height))(ys)
    h_mirrored = jax.jit(jax.vmap(mirrored.height))(-ys)
    np.testing.assert_allclose(h, h_mirrored, atol=1e-15)


def _points_near_head(count, seed=3):
    """Per rail, ``count`` points from 3 mm inside the head to 20 mm outside it, past both
    domain ends too: their (eta, zeta) [m], and by brute force over the domain, sampled
    every 2 um, the nearest point's coordinate [m] and its distance [m]."""
    rng = np.random.default_rng(seed)
    etas, zetas, nearest, distances = [], [], [], []
    for key in KEYS:
        rail = RAILS[key]
        lo, hi = rail.domain
        u = rng.uniform(lo - 4 * MM, hi + 4 * MM, count)
        at = np.clip(u, lo, hi)
        h, s, _ = (np.asarray(v) for v in jax.vmap(rail.height_derivatives)(jnp.asarray(at)))
        offset = rng.uniform(-3 * MM, 20 * MM, count)
        eta = u + offset * -s / np.sqrt(1 + s * s)
        zeta = h + (u - at) * s + offset / np.sqrt(1 + s * s)
        grid = np.linspace(lo, hi, int((hi - lo) / 2e-6) + 1)
        surface = np.asarray(jax.vmap(rail.height)(jnp.asarray(grid)))
        distance = (eta[:, None] - grid) ** 2 + (zeta[:, None] - surface) ** 2
        closest = np.argmin(distance, axis=1)
        etas.append(eta), zetas.append(zeta), nearest.append(grid[closest])
        distances.append(np.sqrt(distance[np.arange(count), closest]))
    return etas, zetas, nearest, distances


@jax.jit
def _feet(rails, eta, zeta):
    return [jax.vmap(rail.normal_foot)(e, z) for rail, e, z in zip(rails, eta, zeta)]


def test_normal_foot_is_the_nearest_point_of_the_head():
    """The closed-form foot of the normal (arcs and flanks by sector) against a brute-
    force nearest point over the domain, sampled every 2 um, for points from 3 mm inside
    the head to 20 mm outside it, past both domain ends too; where the foot is inside
    the domain, eq. (15)'s residual (eta - u) + (zeta - f(u)) f'(u) vanishes; and its
    derivative (jit, vmap, grad) against central differences."""
    count = 400
    etas, zetas, nearest, _ = _points_near_head(count)
    feet = _feet(tuple(RAILS[k] for k in KEYS), jnp.asarray(np.array(etas)),
                 jnp.asarray(np.array(zetas)))
    for key, eta, zeta, near, foot in zip(KEYS, etas, zetas, nearest, feet):
        rail, foot = RAILS[key], np.asarray(foot)
        np.testing.assert_allclose(foot, near, atol=2.5e-6, err_msg=key)
        lo, hi = rail.domain
        inside = (foot > lo) & (foot < hi)
        assert inside.sum() > 0.7 * count and (~inside).sum() > 0.05 * count
        f, f1, _ = (np.asarray(v) for v in jax.vmap(rail.height_derivatives)(jnp.asarray(foot)))
        residual = (eta - foot) + (zeta - f) * f1
        assert np.max(np.abs(residual[inside])) < 1e-13, key
    rail, eta, zeta = RAILS["1:40"], float(etas[1][0]), float(zetas[1][0])
    du = jax.jit(jax.grad(rail.normal_foot, argnums=(0, 1)))(eta, zeta)
    for k, h in enumerate((1e-7, 1e-7)):
        plus = rail.normal_foot(eta + h * (k == 0), zeta + h * (k == 1))
        minus = rail.normal_foot(eta - h * (k == 0), zeta - h * (k == 1))
        assert float(du[k]) == pytest.approx(float(plus - minus) / (2 * h), rel=1e-6, abs=1e-9)


@jax.jit
def _foot_depths(rails, eta, zeta):
    return [jax.vmap(rail.normal_foot_depth)(e, z) for rail, e, z in zip(rails, eta, zeta)]


def test_normal_foot_depth_is_the_distance_to_the_head():
    """The closed-form depth (radius less the distance from an arc's centre, the distance
    below a flank) against the brute-force distance to the sampled head where the foot
    is inside the domain (positive below the surface), against the distance below the
    end's tangent line past a domain end; its derivatives in the point and in the
    inclination (jit, vmap, grad) against central differences; finite at an arc's
    centre."""
    count = 400
    etas, zetas, _, distances = _points_near_head(count, seed=5)
    rails = tuple(RAILS[k] for k in KEYS)
    eta_all, zeta_all = jnp.asarray(np.array(etas)), jnp.asarray(np.array(zetas))
    depths, feet = _foot_depths(rails, eta_all, zeta_all), _feet(rails, eta_all, zeta_all)
    for key, eta, zeta, distance, depth, foot in zip(KEYS, etas, zetas, distances, depths, feet):
        rail, depth, foot = RAILS[key], np.asarray(depth), np.asarray(foot)
        lo, hi = rail.domain
        inside = (foot > lo) & (foot < hi)
        below = zeta < np.asarray(jax.vmap(rail.height)(jnp.asarray(eta)))
        f, f1, _ = (np.asarray(v) for v in jax.vmap(rail.height_derivatives)(jnp.asarray(foot)))
        # The nearest sample lies within half a step of 2 um in y, an arc length of
        # a = 1 um sqrt(1 + f'^2), of the foot: farther by at most a^2 (1 + d / 13 mm) / (2 d)
        # at a distance d.
        arc = 1e-6 * np.sqrt(1 + f1 * f1)
        excess = distance - np.abs(depth)
        bound = np.minimum(arc**2 * (1 + distance / 13e-3) / (2 * distance), arc) + 1e-15
        assert np.all(((excess > -1e-15) & (excess < bound))[inside]), key
        assert np.all(((depth > 0) == below)[inside & (distance > 1e-6)]), key
        tangent = -((zeta - f) - (eta - foot) * f1) / np.sqrt(1 + f1 * f1)
        assert (~inside).sum() > 0.05 * count
        np.testing.assert_allclose(depth[~inside], tangent[~inside], atol=1e-15, err_msg=key)

    def depth_of(theta, eta, zeta):
        rail = eqx.tree_at(lambda r: r.inclination, RAILS["1:40"], theta)
        return rail.normal_foot_depth(eta, zeta)

    grad = jax.jit(jax.vmap(jax.grad(depth_of, argnums=(0, 1, 2)), in_axes=(None, 0, 0)))
    theta = RAILS["1:40"].inclination
    picked = np.arange(0, count, 40)
    eta, zeta = etas[1][picked], zetas[1][picked]
    exact = grad(theta, jnp.asarray(eta), jnp.asarray(zeta))
    step = 1e-7
    for k in range(3):
        args = [np.full(eta.shape, float(theta)), eta, zeta]
        plus, minus = [a.copy() for a in args], [a.copy() for a in args]
        plus[k] += step
        minus[k] -= step
        fd = (np.array([depth_of(*a) for a in zip(*plus)])
              - np.array([depth_of(*a) for a in zip(*minus)])) / (2 * step)
        np.testing.assert_allclose(exact[k], fd, rtol=1e-6, atol=1e-8, err_msg=f"argument {k}")
    # at the centre of the gauge-side R13 corner arc (piece 1) the distance is the radius
    table = RAILS["1:40"]._table()
    centre = (table[1, 0], table[1, 4])
    at_centre = jax.grad(depth_of, argnums=(1, 2))(theta, *centre)
    assert np.all(np.isfinite(np.asarray(at_centre)))
