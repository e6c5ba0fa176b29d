"""Patches from strip depths: separate runs, two maxima in one run (conformal two-point
contact) sharing the interpenetration below their saddle, continuity through the birth
of a maximum and the hand-over between maxima, the strip weights and the centre of a
wide patch, jit/vmap/grad."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.patches import find_patches, overlap_centre

Y = jnp.linspace(-30e-3, 30e-3, 61)  # strips 1 mm apart [m]


def bump(centre, height, width):
    """A parabolic depth cap [m]: height at centre, zero at centre +- width."""
    return height * (1.0 - ((Y - centre) / width) ** 2)


def two_regions(share):
    """Tread (-12 mm) and flange root (+12 mm) depths of one conformal run: ``share``
    moves the interpenetration from the first region to the second."""
    return jnp.maximum(bump(-12e-3, 100e-6 * (1.0 - share), 15e-3),
                       bump(12e-3, 100e-6 * share, 15e-3)) + 10e-6


def effective(depth, slots=3):
    """Depth kept by each slot's maximum [m], and find_patches' outputs, with the keep
    fraction turned back into the cut [m] on the strip depth."""
    index, found, keep, _ = find_patches(depth, slots)
    strip_depth = np.asarray(depth)[index]
    cut = np.where(found, (1.0 - np.asarray(keep)) * strip_depth, 0.0)
    return np.where(found, np.asarray(keep) * strip_depth, 0.0), index, found, cut


def test_separate_runs_are_separate_patches_without_cut():
    depth = jnp.maximum(bump(-15e-3, 50e-6, 4e-3), bump(10e-3, 80e-6, 4e-3)) - 1e-6
    _, index, found, cut = effective(depth)
    assert list(np.asarray(found)) == [True, True, False]
    assert [float(Y[i]) for i in index[:2]] == pytest.approx([-15e-3, 10e-3])
    np.testing.assert_array_equal(np.asarray(cut), 0.0)


def test_one_maximum_is_one_patch_at_its_strip():
    depth = bump(3e-3, 60e-6, 8e-3)
    _, index, found, cut = effective(depth)
    assert list(np.asarray(found)) == [True, False, False]
    assert float(Y[index[0]]) == pytest.approx(3e-3) and float(cut[0]) == 0.0


def test_two_maxima_in_one_run_share_the_saddle_by_hand():
    depth = two_regions(0.4)
    _, index, found, cut = effective(depth)
    d = np.asarray(depth)
    d1, d2 = d[index[0]], d[index[1]]
    s = d[np.argmin(np.where((Y > Y[index[0]]) & (Y < Y[index[1]]), d, np.inf))]
    assert s > 0.0 and list(np.asarray(found)) == [True, True, False]
    expected_cut = [s * (d2 - s) / (d1 + d2 - 2 * s), s * (d1 - s) / (d1 + d2 - 2 * s)]
    np.testing.assert_allclose(cut[:2], expected_cut, rtol=1e-12)
    # the shared base is split, not counted twice: the cuts add up to the saddle
    assert float(cut[0] + cut[1]) == pytest.approx(s, rel=1e-12)


def test_mirror_symmetric():
    depth = two_regions(0.3)
    eff, _, _, _ = effective(depth)
    eff_mirror, _, _, _ = effective(depth[::-1])
    np.testing.assert_allclose(np.sort(eff[:2]), np.sort(eff_mirror[:2]), rtol=1e-12)


def force_proxy(share):
    """Sum over patches of depth^1.5, the shape of the Hertz force."""
    eff, _, _, _ = effective(two_regions(share))
    return float(np.sum(np.maximum(eff, 0.0) ** 1.5))


def largest_jump(samples):
    values = np.array([force_proxy(s) for s in samples])
    return np.max(np.abs(np.diff(values)))


def test_load_hands_over_continuously_between_the_regions():
    """Sweeping the interpenetration from the tread region to the flange-root region
    (a maximum born from a shoulder, then the deepest point changing region): the
    force proxy changes by O(step), so halving the step halves the largest change.
    The deepest-point rule alone would jump by the whole depth^1.5 at the crossing."""
    coarse = largest_jump(np.linspace(0.0, 1.0, 201))
    fine = largest_jump(np.linspace(0.0, 1.0, 401))
    assert fine < 0.6 * coarse
    # what a single deepest point would do at share 0.5: jump to the other region
    deepest_only = np.array([np.max(np.asarray(two_regions(s))) for s in (0.499, 0.501)])
    assert coarse < 0.05 * float(deepest_only[0]) ** 1.5


def test_jit_vmap_and_finite_gradients():
    shares = jnp.linspace(0.05, 0.95, 7)
    batched = jax.jit(jax.vmap(lambda s: find_patches(two_regions(s), 3)))(shares)
    for k, s in enumerate(shares):
        single = find_patches(two_regions(s), 3)
        for a, b in zip(single, batched):
            np.testing.assert_allclose(np.asarray(a), np.asarray(b[k]), rtol=1e-12, atol=1e-20)

    def total(share):
        depth = two_regions(share)
        index, found, keep, _ = find_patches(depth, 3)
        return jnp.sum(jnp.where(found, keep * depth[index] * 1e6, 0.0) ** 1.5)

    for s in (0.2, 0.3, 0.45):  # away from the birth (0) and the crossing (0.5)
        g = float(jax.grad(total)(s))
        h = 1e-6
        fd = (float(total(s + h)) - float(total(s - h))) / (2 * h)
        assert np.isfinite(g) and g == pytest.approx(fd, rel=1e-4, abs=1e-6)


@pytest.mark.parametrize("depth", [two_regions(0.4), two_regions(0.02),
                                   jnp.maximum(bump(-15e-3, 50e-6, 4e-3), bump(10e-3, 80e-6, 4e-3))])
def test_weights_share_out_each_strips_depth(depth):
    """Every strip's positive depth is shared out among the patches, none counted twice,
    and each maximum's own strip carries the depth it keeps."""
    index, found, keep, weights = find_patches(depth, 3)
    np.testing.assert_allclose(np.sum(weights, axis=0), np.maximum(depth, 0.0), atol=1e-18)
    assert np.all(np.asarray(weights) >= 0.0)
    on = np.asarray(found)
    peak = np.asarray(weights)[np.arange(3), np.asarray(index)]
    np.testing.assert_allclose(peak[on], (np.asarray(keep) * np.asarray(depth)[index])[on], rtol=1e-12)


def test_weights_change_continuously_through_birth_and_hand_over():
    """Sweeping the two-region run from just after the birth of the second maximum
    through the crossing: each patch's share (its area ``m`` and centre ``c``) changes by
    O(step), so halving the step halves the largest change of the slot-order-free sums
    of ``m^1.5`` and ``m^1.5 c``. Assigning whole strips to the deepest maximum instead
    would move the strips beyond the saddle from one patch to the other at once."""
    def largest_change(count):
        def moments(share):
            weights = find_patches(two_regions(share), 3)[3]
            area = jnp.sum(weights, axis=1)
            centre = jnp.sum(weights * Y, axis=1) / jnp.where(area > 0.0, area, 1.0)
            return jnp.array([jnp.sum(area**1.5), jnp.sum(area**1.5 * centre)])

        values = jax.vmap(moments)(jnp.linspace(0.002, 0.9, count))
        return np.max(np.abs(np.diff(np.asarray(values), axis=0)), axis=0)

    coarse, fine = largest_change(101), largest_change(201)
    assert np.all(fine < 0.6 * coarse)


def test_centre_of_a_wide_parabolic_patch():
    """A parabolic overlap 2 w = 16 mm wide and 80 um deep off the strip grid: its
    centre is the vertex, its overlap curvature 2 delta / w^2, and it is far from the
    deepest-point estimate passed in (the blend is 1)."""
    depth = bump(3.3e-3, 80e-6, 8e-3)
    _, found, _, weights = find_patches(depth, 1)
    y, blend, curvature = overlap_centre(weights[0], depth, Y, 0.0)
    assert bool(found[0]) and float(blend) == 1.0
    assert float(y) == pytest.approx(3.3e-3, abs=1e-6)
    assert float(curvature) == pytest.approx(2 * 80e-6 / 8e-3**2, rel=0.02)


def test_narrow_patch_keeps_its_deepest_point():
    """A patch narrower than WIDE_FROM (here one strip) is located at the refined
    deepest point given; blending in the centre is continuous in its breadth."""
    depth = bump(0.2e-3, 20e-6, 1.2e-3)
    _, _, _, weights = find_patches(depth, 1)
    y, blend, _ = overlap_centre(weights[0], depth, Y, 0.2e-3)
    assert float(blend) == 0.0 and float(y) == 0.2e-3
    widths = np.linspace(2e-3, 6e-3, 81)  # through the whole blend
    centres = np.array([float(overlap_centre(*(lambda d: (find_patches(d, 1)[3][0], d))(bump(0.3e-3, 50e-6, w)),
                                             Y, 0.3e-3)[0]) for w in widths])
    assert np.max(np.abs(np.diff(centres))) < 2e-6


def test_top_indices_equals_lax_top_k():
    """find_patches' arg-max ranking gives lax.top_k's indices, ties included."""
    from jaxrail.contact.patches import _top_indices

    rng = np.random.default_rng(3)
    for row in (rng.normal(size=132), np.round(rng.normal(size=132), 1),
                np.full(132, -2.0e3), np.r_[np.full(130, -2.0e3), 1.0, 1.0]):
        row = jnp.asarray(row)
        for k in (1, 3, 6):
            np.testing.assert_array_equal(_top_indices(row, k), jax.lax.top_k(row, k)[1])


def test_first_argmax_equals_argmax():
    """first_argmax (a maximum, then the first index within 1e-9 of it) gives jnp.argmax's
    index along any axis, ties and infinities included, under jit and vmap; the first of
    two entries 1e-12 apart; the last index where the maximum is NaN."""
    from jaxrail.contact.patches import first_argmax

    rng = np.random.default_rng(7)
    rows = jnp.asarray(np.stack([rng.normal(size=(5, 131)), np.round(rng.normal(size=(5, 131))),
                                 np.full((5, 131), -1.0e3), np.full((5, 131), -np.inf)]))
    for axis in (-1, 0, 1, 2):
        np.testing.assert_array_equal(jax.jit(first_argmax, static_argnums=1)(rows, axis),
                                      jnp.argmax(rows, axis=axis))
    np.testing.assert_array_equal(jax.vmap(jax.vmap(first_argmax))(rows), jnp.argmax(rows, axis=-1))
    assert int(first_argmax(jnp.array([1.0, jnp.inf, 2.0, jnp.inf]))) == 1
    assert int(first_argmax(jnp.array([0.5, 2.0, 2.0 + 2e-12, 1.0]))) == 1
    assert int(first_argmax(jnp.array([1.0, jnp.nan, 2.0]))) == 2
