"""find_patches and overlap_density against brute-force references written from their
docstrings with plain Python loops (peaks, saddles, cuts, basins; the moments by
Gauss-Legendre quadrature of the piecewise-linear density), on random rows of strips with several
maxima, runs broken by non-members and exact ties; and the search compiled without a
scatter or a sort (so that a loop holding it compiles into one kernel)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact.patches import CANDIDATE_DEPTH, find_patches, overlap_density

NO = -1.0e3


def _cut_toward(s, own, other):
    total = (own - s) + (other - s)
    return s * (other - s) / total if s > 0.0 and total > 0.0 else 0.0


def reference_patches(depth, k, candidate_depth=CANDIDATE_DEPTH):
    """find_patches' outputs by loops over the strips (its docstring, step by step)."""
    d = [float(x) for x in depth]
    n = len(d)
    member = []
    for i in range(n):
        dm, dp = d[max(i - 1, 0)], d[min(i + 1, n - 1)]
        local_max = (d[i] >= dm and d[i] > dp) or (d[i] > dm and d[i] >= dp)
        bend = 2.0 * d[i] - dm - dp
        peak = d[i] + ((dm - dp) ** 2 / (8.0 * bend) if bend > 0.0 else 0.0)
        member.append(d[i] > 0.0 or (local_max and peak > -candidate_depth))
    inside = [d[i] if member[i] else NO for i in range(n)]
    peaks = []
    for i in range(n):
        left = inside[i - 1] if i > 0 else NO
        right = inside[i + 1] if i < n - 1 else NO
        if member[i] and ((inside[i] >= left and inside[i] > right)
                          or (inside[i] > left and inside[i] >= right)):
            peaks.append(i)
    m = len(peaks)
    top = [inside[p] for p in peaks]
    saddle = [min(inside[peaks[j]:peaks[j + 1]]) for j in range(m - 1)]  # after peak j
    cut_right = [_cut_toward(saddle[j], top[j], top[j + 1]) if j < m - 1 else 0.0
                 for j in range(m)]
    cut_left = [_cut_toward(saddle[j - 1], top[j], top[j - 1]) if j > 0 else 0.0
                for j in range(m)]
    cut = [max(a, b) for a, b in zip(cut_left, cut_right)]
    best = sorted(range(m), key=lambda j: (-(top[j] - cut[j]), j))[:k]
    chosen = sorted(best)
    index = np.zeros(k, int)
    found = np.zeros(k, bool)
    keep = np.ones(k)
    for slot, j in enumerate(chosen):
        index[slot], found[slot] = peaks[j], True
        if cut[j] > 0.0:
            keep[slot] = 1.0 - cut[j] / top[j]
    # basins: a strip goes with the peak on its side of the first strip at the saddle
    weights = np.zeros((k, n))
    for i in range(n):
        before = [j for j in range(m) if peaks[j] <= i]
        if not before:
            b = 0
        elif before[-1] == m - 1:
            b = m - 1
        else:
            j = before[-1]
            low = next(s for s in range(peaks[j], peaks[j + 1]) if inside[s] == saddle[j])
            b = j if i <= low else j + 1
        if m == 0:
            continue
        level_left = max(saddle[b - 1], 0.0) if b > 0 else 0.0
        level_right = max(saddle[b], 0.0) if b < m - 1 else 0.0
        toward_right = level_right >= level_left
        level = level_right if toward_right else level_left
        c = cut_right[b] if toward_right else cut_left[b]
        neighbour = b + 1 if toward_right else b - 1
        kept = (level - c) / level if level > 0.0 else 1.0
        positive = max(d[i], 0.0)
        above = max(positive - level, 0.0)
        below = positive - above
        for slot, j in enumerate(chosen):
            if j == b:
                weights[slot, i] += above + kept * below
            if j == neighbour:
                weights[slot, i] += (1.0 - kept) * below
    return index, found, keep, weights


def random_rows(count, n, seed):
    """Depth rows [m]: up to five parabolic caps over a clear floor, some with noise
    (many small maxima), some rounded to 10 um (exact ties and plateaus)."""
    rng = np.random.default_rng(seed)
    y = np.linspace(-0.07, 0.06, n)
    rows = []
    for r in range(count):
        depth = -rng.uniform(1e-4, 3e-3) * np.ones(n)
        for _ in range(rng.integers(0, 6)):
            centre, width = rng.uniform(-0.07, 0.06), rng.uniform(0.001, 0.02)
            cap = rng.uniform(-3e-4, 2e-3) - rng.uniform(1e-4, 2e-3) * ((y - centre) / width) ** 2
            depth = np.maximum(depth, cap)
        if r % 4 == 1:
            depth = depth + rng.normal(0.0, 2e-5, n)
        if r % 4 == 2:
            depth = np.round(depth, 5)
        rows.append(depth)
    return np.array(rows)


@pytest.mark.parametrize("slots", [1, 3])
def test_find_patches_against_the_loops(slots):
    rows = random_rows(300, 131, seed=slots)
    index, found, keep, weights = jax.jit(jax.vmap(lambda d: find_patches(d, slots)))(
        jnp.asarray(rows))
    several = 0
    for r, depth in enumerate(rows):
        i_ref, f_ref, k_ref, w_ref = reference_patches(depth, slots)
        several += int(np.sum(f_ref) > 1)
        np.testing.assert_array_equal(np.asarray(found[r]), f_ref)
        np.testing.assert_array_equal(np.asarray(index[r]), i_ref)
        np.testing.assert_allclose(np.asarray(keep[r]), k_ref, rtol=1e-14, atol=0.0)
        np.testing.assert_allclose(np.asarray(weights[r]), w_ref, rtol=1e-13, atol=1e-19)
    if slots > 1:
        assert several > 50  # the rows exercise shared runs and several patches


def reference_moments(weights, depth, y, origin):
    """Zeroth to second moments about ``origin`` of the density linear between strips,
    falling to zero where the linear interpolant of ``depth`` crosses zero: per
    segment, the piece where the density is linear, by 3-point Gauss-Legendre (exact for
    the cubic integrands)."""
    nodes, gauss = np.polynomial.legendre.leggauss(3)
    moments = np.zeros(3)
    for i in range(len(y) - 1):
        d0, d1 = depth[i], depth[i + 1]
        if d0 <= 0.0 and d1 <= 0.0:
            continue
        a = weights[i] if d0 > 0.0 else 0.0
        b = weights[i + 1] if d1 > 0.0 else 0.0
        lo, hi = y[i], y[i + 1]
        cross = lo + d0 / (d0 - d1) * (hi - lo) if (d0 > 0.0) != (d1 > 0.0) else None
        if d0 > 0.0 and d1 <= 0.0:
            lo, hi, b = lo, cross, 0.0  # from a at the strip to zero at the crossing
        elif d1 > 0.0 and d0 <= 0.0:
            lo, hi, a = cross, hi, 0.0
        x = 0.5 * (lo + hi) + 0.5 * (hi - lo) * nodes
        density = a + (x - lo) / (hi - lo) * (b - a)
        for k in range(3):
            moments[k] += 0.5 * (hi - lo) * np.sum(gauss * density * (x - origin) ** k)
    return moments


def test_overlap_density_of_several_patches_against_quadrature():
    """All slots at once against the moments by quadrature (centre, breadth, curvature
    from them as the docstring defines)."""
    y = np.linspace(-0.03, 0.03, 61)
    rows = random_rows(40, 61, seed=7)

    def slots(depth):
        index, found, _, weights = find_patches(depth, 3)
        origin = jnp.asarray(y)[index] + 2e-4
        return (found, weights, origin,
                *overlap_density(weights, depth, jnp.asarray(y), origin))

    found, weights, origin, centre, breadth, curvature = (
        np.asarray(x) for x in jax.jit(jax.vmap(slots))(jnp.asarray(rows)))
    checked = 0
    for r, depth in enumerate(rows):
        for slot in np.flatnonzero(found[r]):
            w = weights[r, slot]
            m0, m1, m2 = reference_moments(w, depth, y, origin[r, slot])
            if m0 <= 0.0:
                continue
            variance = m2 / m0 - (m1 / m0) ** 2
            assert centre[r, slot] == pytest.approx(origin[r, slot] + m1 / m0, abs=1e-15)
            assert breadth[r, slot] == pytest.approx(m0 / w.max(), rel=1e-12)
            assert curvature[r, slot] == pytest.approx(0.4 * w.max() / variance, rel=1e-9)
            checked += 1
    assert checked > 30


def test_search_compiles_without_scatter_or_sort():
    """The search's program holds no scatter, sort or custom call: XLA:CPU
    compiles a loop holding it (the integrator's stages) into one kernel only then."""
    from jaxrail.contact import search_wheel
    from jaxrail.profiles import s1002, uic60
    from jaxrail.track import Rails, straight_track

    track = straight_track(100.0, rails=Rails.at_gauge(uic60("1:40"), 1.435))
    wheel = s1002()
    rotation = jnp.eye(3)
    lowered = jax.jit(lambda p: search_wheel(wheel, track, p, rotation, 1.0)).lower(
        jnp.array([10.0, 0.0, 0.46]))
    text = lowered.as_text()
    assert "stablehlo.while" in text  # the rail foot's Newton steps: a program was read
    for opcode in ("stablehlo.scatter", "stablehlo.sort", "stablehlo.custom_call"):
        assert opcode not in text, opcode
