"""Wear distribution (jaxrail.wear.distribution, with patch_wear): conservation of the
deposited volume and of the height loss against the totals (hand sums), the linear
weights at and between nodes (by hand), a real FASTSIM/ArchardKTH patch deposited on a
profile grid against PatchWear.rate and the contact point (symmetry), strip_positions
against the hand formula y_c + side cos(angle) offset, and the deposit's derivative
against central differences."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.wear.distribution import deposit, height_loss, lateral_grid, strip_positions
from jaxrail.wear.laws import ArchardKTH
from jaxrail.wear.patch_wear import patch_wear

N, MU, A, B, SPEED = 8.0e4, 0.4, 6.0e-3, 5.0e-3, 30.0
CONSERVE_RTOL = 1e-12  # deposits and heights against the total volume
WEAR_RTOL = 1e-6  # the issue's must-show: profile integral against the patches' volume
CENTROID_ATOL = 1e-9  # [m]
FD_RTOL = 1e-6


def test_lateral_grid_spacing_and_ends():
    nodes = lateral_grid((-0.07, 0.05), 0.5e-3)
    assert nodes[0] == -0.07 and nodes[-1] == 0.05
    assert len(nodes) == 241
    np.testing.assert_allclose(np.diff(nodes), 0.5e-3, rtol=1e-9)


def test_deposit_conserves_random_volumes_including_beyond_the_ends():
    rng = np.random.default_rng(7)
    nodes = lateral_grid((-0.03, 0.02), 1e-3)
    positions = rng.uniform(-0.05, 0.04, size=(7, 31))  # some beyond both ends
    assert (positions < nodes[0]).any() and (positions > nodes[-1]).any()
    volumes = rng.uniform(0.0, 1e-9, size=positions.shape)
    out = np.asarray(deposit(nodes, positions, volumes))
    assert out.shape == nodes.shape
    assert np.all(out >= 0.0)
    assert out.sum() == pytest.approx(volumes.sum(), rel=CONSERVE_RTOL)
    # beyond the ends: everything on the end nodes
    below = positions < nodes[0]
    only_below = np.asarray(deposit(nodes, positions[below], volumes[below]))
    assert only_below[0] == pytest.approx(volumes[below].sum(), rel=CONSERVE_RTOL)
    assert np.all(only_below[1:] == 0.0)
    above = positions > nodes[-1]
    only_above = np.asarray(deposit(nodes, positions[above], volumes[above]))
    assert only_above[-1] == pytest.approx(volumes[above].sum(), rel=CONSERVE_RTOL)
    assert np.all(only_above[:-1] == 0.0)
    # height loss: sum(dh) * spacing * length is the total volume
    length = 2.0 * math.pi * 0.46  # a wheel's circumference [m]
    dh = np.asarray(height_loss(nodes, out, length))
    spacing = nodes[1] - nodes[0]
    assert dh.sum() * spacing * length == pytest.approx(volumes.sum(), rel=CONSERVE_RTOL)


def test_deposit_on_a_node_and_halfway():
    nodes = np.linspace(-0.01, 0.01, 21)  # spacing 1 mm
    out = np.asarray(deposit(nodes, np.array([nodes[7]]), np.array([3.0])))
    expected = np.zeros(21)
    expected[7] = 3.0
    # (node - first node) / spacing is an integer up to rounding (the spacing 1 mm is
    # not a binary fraction): a few ulps may land on the neighbour
    np.testing.assert_allclose(out, expected, atol=1e-13 * 3.0)
    # the last node too (upper end of the grid)
    out = np.asarray(deposit(nodes, np.array([nodes[-1]]), np.array([2.0])))
    assert out[-1] == pytest.approx(2.0, rel=1e-15) and np.all(out[:-1] == 0.0)
    halfway = 0.5 * (nodes[12] + nodes[13])
    out = np.asarray(deposit(nodes, np.array([halfway]), np.array([4.0])))
    assert out[12] == pytest.approx(2.0, rel=1e-12) and out[13] == pytest.approx(2.0, rel=1e-12)
    assert np.sum(np.abs(out)) == pytest.approx(4.0, rel=1e-12)
    # a quarter of the way: 3/4 on the lower node, 1/4 on the upper (linear weights)
    quarter = nodes[4] + 0.25 * (nodes[5] - nodes[4])
    out = np.asarray(deposit(nodes, np.array([quarter]), np.array([4.0])))
    assert out[4] == pytest.approx(3.0, rel=1e-12) and out[5] == pytest.approx(1.0, rel=1e-12)


def _patch(xi, eta, phi):
    return patch_wear(ArchardKTH(), N, A, B, xi, eta, phi, MU, SPEED)


@pytest.mark.parametrize("side_sign,contact_y,angle", [(1.0, 0.004, 0.05), (-1.0, -0.012, 0.3)])
def test_real_patch_deposit_integrates_to_the_patch_wear(side_sign, contact_y, angle):
    wear = _patch(5e-4, 3e-4, 0.0)  # partial slip, no spin: symmetric in y
    assert float(wear.slip_area) > 0.0
    assert float(wear.rate) > 0.0
    nodes = lateral_grid((-0.04, 0.03), 0.5e-3)
    positions = strip_positions(jnp.asarray(contact_y), jnp.asarray(angle),
                                wear.strip_offset, side_sign)
    # all strips land inside the grid (no end-node clipping)
    assert float(positions.min()) > nodes[0] and float(positions.max()) < nodes[-1]
    out = np.asarray(deposit(nodes, positions, wear.strip_rate))
    assert out.sum() == pytest.approx(float(wear.rate), rel=WEAR_RTOL)
    # by symmetry in y the strip rates are mirror images, so the deposit's centroid
    # (kept by linear weights inside the grid) is the contact point
    rates = np.asarray(wear.strip_rate)
    np.testing.assert_allclose(rates, rates[::-1], rtol=1e-9)
    centroid = np.sum(nodes * out) / out.sum()
    assert abs(centroid - contact_y) < CENTROID_ATOL


def test_spin_moves_the_centroid_off_the_contact_point():
    # a check that the symmetry test above can fail: spin breaks the y symmetry
    wear = _patch(5e-4, 3e-4, 2.0)
    nodes = lateral_grid((-0.04, 0.03), 0.5e-3)
    out = np.asarray(deposit(nodes, strip_positions(jnp.asarray(0.0), jnp.asarray(0.0),
                                                    wear.strip_offset, 1.0), wear.strip_rate))
    assert abs(np.sum(nodes * out) / out.sum()) > 1e3 * CENTROID_ATOL


def test_patch_wear_areas():
    full = _patch(0.05, 0.0, 0.0)
    assert float(full.area) == pytest.approx(math.pi * A * B, rel=5e-3)
    assert float(full.slip_area) == pytest.approx(float(full.area), rel=1e-12)


def test_patch_wear_slip_area_is_the_ellipse_at_full_slip():
    full = _patch(0.05, 0.0, 0.0)
    assert float(full.slip_area) == pytest.approx(math.pi * A * B, rel=5e-3)


def test_strip_positions_sides_and_tilt():
    offsets = jnp.array([-2e-3, 0.0, 1e-3, 3e-3])
    angle = 0.4
    left = np.asarray(strip_positions(jnp.asarray(0.01), jnp.asarray(angle), offsets, 1.0))
    right = np.asarray(strip_positions(jnp.asarray(0.01), jnp.asarray(angle), offsets, -1.0))
    np.testing.assert_allclose(left, 0.01 + np.asarray(offsets) * math.cos(angle), rtol=1e-15)
    np.testing.assert_allclose(right, 0.01 - np.asarray(offsets) * math.cos(angle), rtol=1e-15)
    assert left[3] > 0.01 and right[3] < 0.01  # positive offset: field side on the left
    # batched contact points: (P,) contact_y with (P, strips) offsets
    ys, angles = jnp.array([0.0, 0.02]), jnp.array([0.0, 1.0])
    both = np.asarray(strip_positions(ys, angles, jnp.stack([offsets, offsets]), 1.0))
    np.testing.assert_allclose(both[0], np.asarray(offsets), rtol=1e-15)
    np.testing.assert_allclose(both[1], 0.02 + np.asarray(offsets) * math.cos(1.0), rtol=1e-15)


@pytest.mark.parametrize("position", [0.00237, -0.0061])
def test_deposit_gradient_wrt_position(position):
    nodes = np.linspace(-0.01, 0.01, 21)
    volume = 2.5e-9
    k = int(math.floor((position - nodes[0]) / (nodes[1] - nodes[0])))

    def at_node(pos, j):
        return deposit(nodes, jnp.reshape(pos, (1,)), jnp.array([volume]))[j]

    for j, sign in [(k, -1.0), (k + 1, 1.0)]:
        grad = float(jax.grad(at_node)(position, j))
        h = 1e-7
        fd = (float(at_node(position + h, j)) - float(at_node(position - h, j))) / (2 * h)
        assert grad == pytest.approx(fd, rel=FD_RTOL)
        # by hand: the weight moves by volume / spacing per metre
        assert grad == pytest.approx(sign * volume / 1e-3, rel=1e-9)
    assert float(jax.grad(at_node)(position, k + 3)) == 0.0
