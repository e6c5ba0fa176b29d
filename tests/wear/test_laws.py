"""Wear laws (jaxrail.wear.laws): Archard/KTH volume rates against hand sums
k p v dA / H (FASTSIM full slip and hand-made grids), the KTH map's published
coefficients and edges (Jendel 2002), the USFD rate at its regions' ends against the
published constants (Braghin et al. 2006) and its volume rate against the hand unit
conversion, the input checks, and the blended map's derivatives against central
differences."""

import math
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.wear.fastsim import PatchGrid, fastsim_patch
from jaxrail.wear.laws import KTH_RANGES, MODELS, USFD, ArchardKTH, check_fields, wear_law

N, MU, A, B = 8.0e4, 0.4, 6.0e-3, 5.0e-3
H = 2.45e9  # the default hardness [Pa]
K1, K2, K3, K4 = 5.5e-4, 35e-4, 5.5e-4, 350e-4  # the defaults (middles of the ranges)

HAND_RTOL = 1e-6  # volume rates against hand sums
EXACT_RTOL = 1e-14  # transition 0: the published constants, rounding only
FAR_RTOL = 1e-6  # default transition, outside the blend bands edge (1 +- 5 %)
FD_RTOL = 1e-5


def _grid(pressure, area, sliding, stick=None, tx=None, ty=None, sx=None, sy=None):
    """A PatchGrid of one strip built by hand (keyword fields)."""
    p = np.atleast_2d(np.asarray(pressure, dtype=float))
    full = lambda v: jnp.asarray(np.broadcast_to(np.asarray(v, dtype=float), p.shape))  # noqa: E731
    zeros = np.zeros(p.shape)
    return PatchGrid(
        x=full(zeros), y=full(zeros), area=full(area), pressure=full(p),
        traction_x=full(zeros if tx is None else tx), traction_y=full(zeros if ty is None else ty),
        slip_x=full(sliding if sx is None else sx), slip_y=full(zeros if sy is None else sy),
        sliding=full(sliding),
        stick=jnp.asarray(np.broadcast_to(False if stick is None else stick, p.shape)),
        strip_y=jnp.zeros(p.shape[0]))


def test_archard_full_slip_fastsim_against_hand_sum():
    law = ArchardKTH(transition=0.0)
    speed = 2.0  # [m/s]: V |s| ~ 0.1 m/s, the k1 region
    grid = fastsim_patch(N, A, B, 0.05, 0.0, 0.0, MU)
    stick = np.asarray(grid.stick)
    assert not stick.any()  # every element slides
    p = np.asarray(grid.pressure)
    area = np.broadcast_to(np.asarray(grid.area), p.shape)
    # the sliding the law assumes: V |s|, s the local slip; check it is in k1's region
    s = np.hypot(np.asarray(grid.slip_x), np.asarray(grid.slip_y))
    np.testing.assert_allclose(np.asarray(grid.sliding), s, rtol=1e-15)
    v = speed * s
    assert v.max() < 0.2 and p.max() < 0.8 * H
    hand = K1 * np.sum(p * v * area) / H
    ours = float(jnp.sum(law.volume_rate(grid, speed)))
    assert ours == pytest.approx(hand, rel=HAND_RTOL)
    # the pressure carries N (sum p dA = N), so with the mean sliding velocity
    # v_mean = sum p v dA / N the total is k N v_mean / H: in full slip the local slip
    # is the rigid creepage within the traction's gradient term (a few per cent)
    v_mean = np.sum(p * v * area) / N
    assert hand == pytest.approx(K1 * N * v_mean / H, rel=1e-12)
    assert v_mean == pytest.approx(speed * 0.05, rel=5e-2)


def test_archard_hand_grid_with_known_slip_area():
    # five elements: two stick (zero slip), three slide in regions k1, k2, k3;
    # one more at p >= 0.8 H in the seizure region k4
    law = ArchardKTH(transition=0.0)
    speed = 10.0
    pressure = np.array([1.0e9, 1.5e9, 1.0e9, 1.2e9, 0.5e9, 2.1e9])
    area = np.array([1e-6, 2e-6, 1.5e-6, 0.5e-6, 3e-6, 0.2e-6])
    sliding = np.array([0.0, 0.0, 0.01, 0.05, 0.2, 0.03])  # v = 0, 0, 0.1, 0.5, 2.0, 0.3
    stick = sliding == 0.0
    k = np.array([0.0, 0.0, K1, K2, K3, K4])
    hand = np.sum((k * pressure * speed * sliding * area / H)[~stick])
    grid = _grid(pressure, area, sliding, stick)
    rate = np.asarray(law.volume_rate(grid, speed))
    assert np.all(rate[0, stick] == 0.0)
    assert float(np.sum(rate)) == pytest.approx(hand, rel=HAND_RTOL)
    np.testing.assert_allclose(rate[0], k * pressure * speed * sliding * area / H, rtol=1e-12)


@pytest.mark.parametrize("v,p_over_h,k", [
    (0.05, 0.3, K1), (0.45, 0.3, K2), (2.0, 0.3, K3),
    (0.05, 0.95, K4), (0.45, 0.95, K4), (2.0, 0.95, K4)])
def test_kth_map_middles_exact_without_transition(v, p_over_h, k):
    law = ArchardKTH(transition=0.0)
    k_map = float(law.coefficient(jnp.asarray(p_over_h * H), jnp.asarray(v)))
    assert k_map == pytest.approx(k, rel=EXACT_RTOL)


def test_kth_coefficient_accepts_python_scalars_without_transition():
    assert float(ArchardKTH(transition=0.0).coefficient(0.3 * H, 0.05)) == K1


@pytest.mark.parametrize("v,p_over_h,k", [
    (0.02, 0.02, K1), (2.0, 0.02, K3), (0.02, 0.0, K1), (3.0, 0.01, K3)])
def test_kth_map_default_transition_far_from_edges(v, p_over_h, k):
    # far from every edge (and at zero pressure and sliding)
    law = ArchardKTH()
    assert float(law.coefficient(p_over_h * H, v)) == pytest.approx(k, rel=FAR_RTOL)


@pytest.mark.parametrize("v,p_over_h,k", [
    (0.05, 0.3, K1), (2.0, 0.3, K3), (0.45, 0.3, K2), (0.05, 0.95, K4), (0.05, 0.5, K1),
    (0.189, 0.3, K1), (0.211, 0.3, K2), (0.45, 0.759, K2), (0.45, 0.841, K4)])
def test_kth_map_default_transition_holds_the_published_values_outside_the_bands(v, p_over_h, k):
    # the blend is confined to edge (1 +- 5 %): outside it the published values hold
    # (rounding only), just outside the bands included
    law = ArchardKTH()
    assert float(law.coefficient(p_over_h * H, v)) == pytest.approx(k, rel=FAR_RTOL)


@pytest.mark.parametrize("v,p_over_h,below,above", [
    (0.2, 0.3, K1, K2), (0.7, 0.3, K2, K3)])
def test_kth_velocity_edges_without_transition(v, p_over_h, below, above):
    law = ArchardKTH(transition=0.0)
    eps = 1e-9
    p = jnp.asarray(p_over_h * H)
    # k3 = k1 + (k2 - k1) + (k3 - k2): rounding only
    below_k = float(law.coefficient(p, jnp.asarray(v * (1 - eps))))
    above_k = float(law.coefficient(p, jnp.asarray(v * (1 + eps))))
    assert below_k == pytest.approx(below, rel=EXACT_RTOL)
    assert above_k == pytest.approx(above, rel=EXACT_RTOL)


@pytest.mark.parametrize("v,low", [(0.1, K1), (0.45, K2), (0.9, K3)])
def test_kth_pressure_edge_without_transition(v, low):
    law = ArchardKTH(transition=0.0)
    eps = 1e-9
    v = jnp.asarray(v)
    below_k = float(law.coefficient(jnp.asarray(0.8 * H * (1 - eps)), v))
    above_k = float(law.coefficient(jnp.asarray(0.8 * H * (1 + eps)), v))
    assert below_k == pytest.approx(low, rel=EXACT_RTOL)
    assert above_k == pytest.approx(K4, rel=EXACT_RTOL)


def test_usfd_rate_at_the_regions_ends():
    law = USFD()
    rate = lambda i: float(law.rate(i))  # noqa: E731
    eps = 1e-9
    # mild: K = 5.3 I on [0, 10.4)
    assert rate(0.0) == 0.0
    assert rate(5.0) == pytest.approx(5.3 * 5.0, rel=EXACT_RTOL)
    assert rate(10.4 - eps) == pytest.approx(5.3 * 10.4, rel=1e-8)
    # severe: 55.0 on [10.4, 77.2]
    assert rate(10.4) == 55.0
    assert rate(40.0) == 55.0
    assert rate(77.2) == 55.0
    # catastrophic: the published line 61.9 I - 4778.7 is -0.02 at 77.2; the module
    # holds 55 until the line crosses it at I = 4833.7 / 61.9
    assert rate(77.2 + eps) == 55.0
    crossing = 4833.7 / 61.9
    assert rate(crossing - 1e-6) == 55.0
    assert rate(crossing + 1e-3) == pytest.approx(55.0 + 61.9e-3, rel=1e-9)
    assert rate(100.0) == pytest.approx(61.9 * 100.0 - 4778.7, rel=EXACT_RTOL)
    assert rate(law.max_index) == pytest.approx(61.9 * 150.0 - 4778.7, rel=EXACT_RTOL)
    assert law.max_index == 150.0


def test_usfd_volume_rate_against_hand_conversion():
    law = USFD()
    speed = 20.0  # [m/s]
    # indices |tau . s| [N/mm^2] = 5, 50, 100, 0 (stick) from tractions [Pa] and slips
    tx = np.array([-5e8, 0.0, -4e8, -1e9])
    ty = np.array([0.0, -1e9, -3e8, 0.0])
    sx = np.array([0.01, 0.0, 0.16, 0.0])
    sy = np.array([0.0, 0.05, 0.12, 0.0])
    area = np.array([1e-6, 2e-6, 0.5e-6, 1e-6])  # [m^2]
    index = np.abs(tx * sx + ty * sy) / 1e6
    np.testing.assert_allclose(index, [5.0, 50.0, 100.0, 0.0], rtol=1e-12)
    k = np.array([5.3 * 5.0, 55.0, 61.9 * 100.0 - 4778.7, 0.0])  # [ug/(m mm^2)]
    hand = k * (area * 1e6) * speed * 1e-9 / 7800.0  # [m^3/s]
    grid = _grid(np.ones(4), area, np.hypot(sx, sy), sx == 0, tx, ty, sx, sy)
    rate = np.asarray(law.volume_rate(grid, speed))[0]
    np.testing.assert_allclose(rate, hand, rtol=HAND_RTOL)
    assert float(np.sum(rate)) == pytest.approx(float(np.sum(hand)), rel=HAND_RTOL)
    # density enters inversely
    heavy = np.asarray(USFD(density=2 * 7800.0).volume_rate(grid, speed))[0]
    np.testing.assert_allclose(heavy, hand / 2, rtol=HAND_RTOL)


def test_wear_law_unknown_name():
    with pytest.raises(ValueError) as err:
        wear_law("nonsense")
    message = str(err.value)
    assert "nonsense" in message
    for name in MODELS:
        assert name in message
    assert set(MODELS) == {"archard-kth", "usfd"}


def test_wear_law_out_of_range_coefficient():
    with pytest.raises(ValueError) as err:
        wear_law("archard-kth", k4=0.5)
    message = str(err.value)
    low, high = KTH_RANGES["k4"]
    assert "k4" in message and "0.5" in message
    assert f"{low:g}" in message and f"{high:g}" in message
    assert (low, high) == (300e-4, 400e-4)


def test_wear_law_accepts_in_range_and_returns_the_law():
    law = wear_law("archard-kth", k1=5e-4)
    assert isinstance(law, ArchardKTH) and float(law.k1) == 5e-4
    assert isinstance(wear_law("usfd"), USFD)
    with pytest.raises(ValueError, match="hardness"):
        wear_law("archard-kth", hardness=0.0)


@pytest.mark.parametrize("fields,words", [
    ({"k9": 1e-4}, ["k9", "k1", "hardness"]),
    ({"k2": "32e-4"}, ["k2", "finite number"]),
    ({"k2": True}, ["k2", "finite number"]),
    ({"hardness": float("nan")}, ["hardness", "finite number"]),
])
def test_check_fields_names_what_is_wrong(fields, words):
    with pytest.raises(ValueError) as err:
        check_fields("archard-kth", fields)
    for word in words:
        assert word in str(err.value)


def test_a_route_file_is_checked_without_building_the_law():
    """parse_route checks [wear] on plain numbers: with float64 off and warnings as
    errors, building the law (a float64 JAX array) would raise; parsing does not, and
    building it afterwards does (so the probe can fail)."""
    route = "\n".join(['name = "r"', 'scenario = "paper-curve"', "duration = 10.0",
                       "[wear]", "k2 = 32e-4", "[[sections]]", "weight = 1.0",
                       "speed = 20.0", "radius = 500.0", "cant = 0.1", ""])
    program = "\n".join([
        "import jax, warnings",
        "jax.config.update('jax_enable_x64', False)",
        "warnings.simplefilter('error')",
        "from jaxrail.wear.route import parse_route",
        f"route = parse_route({route!r})",
        "assert route.wear == {'k2': 32e-4}",
        "try:",
        "    route.law()",
        "except UserWarning as warning:",
        "    assert 'float64' in str(warning)",
        "else:",
        "    raise SystemExit('building the law did not warn')",
    ])
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]


def test_usfd_negative_density_raises():
    with pytest.raises(ValueError, match="density"):
        USFD(density=-1.0).check()


@pytest.mark.parametrize("v,p_over_h", [(0.205, 0.3), (0.69, 0.5), (0.1, 0.79)])
def test_kth_coefficient_gradients_against_central_differences(v, p_over_h):
    law = ArchardKTH()
    coefficient = jax.jit(lambda p, v: law.coefficient(p, v))
    p = p_over_h * H
    dk_dp, dk_dv = (float(g) for g in jax.jit(jax.grad(
        lambda p, v: law.coefficient(p, v), argnums=(0, 1)))(p, v))
    # steps of 1e-3 and 1e-4 logistic widths (0.05 edge): truncation ~1e-7, and the
    # difference stays far above rounding even where the slope is a tail's
    hv, hp = 1e-5, 1e-4 * 0.04 * H
    fd_v = (float(coefficient(p, v + hv)) - float(coefficient(p, v - hv))) / (2 * hv)
    fd_p = (float(coefficient(p + hp, v)) - float(coefficient(p - hp, v))) / (2 * hp)
    assert dk_dv == pytest.approx(fd_v, rel=FD_RTOL)
    assert dk_dp == pytest.approx(fd_p, rel=FD_RTOL)
    # near an edge the slope is large: not a flat step
    assert abs(dk_dv) * v + abs(dk_dp) * p > 1e-3 * K1
