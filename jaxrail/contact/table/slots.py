"""Slot tracking at build time: the patches the search finds at each node of a table's
grid are put into slots so that a slot holds the same patch from node to node and the
interpolation does not mix two patches (:mod:`jaxrail.contact.table`); and the bound on
the geometry's rates across levels."""

import itertools

import numpy as np

from .grid import _RATES, _VALUES, _WHERE

_CLEAR = 1.0e-3  # [m] slots that never hold a patch: this far clear of the rail
# [m] per node: where its patch has gone, a slot's depth falls below the rail within one
# node and on by the patch's own trend (no kink for the spline to ring at), at least
# _RAMP_MIN and at most _RAMP; across yaw and roll by _RAMP
_RAMP = 3.0e-5
_RAMP_MIN = 1.0e-6
_TRACK_JUMP = 1.0e-2  # [m] largest move of a patch on the wheel between lateral nodes
_MATCH_LIMIT = 1.0  # [m] between levels and yaw or roll nodes: pair as many as there are


def _distance(a, b):
    """How far apart two patches are [m], each given as (contact point [m], deepest
    point [m] on the wheel, depth [m], depth slope) (:func:`_key`): their contact
    points; their deepest points, half-weighted (twin maxima sharing one wide
    interpenetration have nearly the same contact point, its centre, but deepest
    points far apart, and which twin survives where the other dies is told by them);
    their depths, ten times; and their slopes (a millimetre per unit). Depths, not
    depth offsets: an offset moves with the wheel's height, which differs from node to
    node (by tenths of a millimetre per node in flange contact)."""
    return (abs(a[0] - b[0]) + 0.5 * abs(a[1] - b[1]) + 10.0 * abs(a[2] - b[2])
            + 1.0e-3 * abs(a[3] - b[3]))


def _key(value, depth):
    """(contact point, deepest point, depth, depth slope) of a patch's values
    (F + 1,) and depth [m]."""
    return np.array([value[_WHERE], value[_VALUES.start], depth, value[1]])


def _pair(old, new, cost, limit):
    """Order-preserving pairs ``(i, j)`` of ``old[i]`` with ``new[j]`` (both sorted along
    the wheel): two patches of one surface are separate maxima of the penetration and
    cannot pass each other on the wheel without merging, so the k-th paired old patch
    goes to the k-th paired new one. Of all such pairings, the one with the least
    ``cost(i, j)`` plus ``limit / 2`` per patch left unpaired; pairs costing ``limit`` or
    more are not allowed."""
    best, best_cost = [], 0.5 * limit * (len(old) + len(new))
    for r in range(1, min(len(old), len(new)) + 1):
        for olds in itertools.combinations(range(len(old)), r):
            for news in itertools.combinations(range(len(new)), r):
                costs = [cost(i, j) for i, j in zip(olds, news)]
                if max(costs) >= limit:
                    continue
                total = sum(costs) + 0.5 * limit * (len(old) + len(new) - 2 * r)
                if total < best_cost:
                    best, best_cost = list(zip(olds, news)), total
    return best


def _track_line(found, values, depth, surfaces, heights):
    """Slot-consistent values (L, P, F) and owned flags (L, P) of one lateral line:
    patches tracked along the lateral axis (:func:`_pair`, each track's next wheel
    coordinate, depth and slope also predicted from its last two nodes: on a conformal
    tread patches move several times their spacing per millimetre of shift), each
    surface's slots assigned in order of birth; empty slots continue their nearest patch
    (:func:`_continue_empty`, at each node's wheel height ``heights`` (L,) [m])."""
    n, p, _ = values.shape
    out = np.zeros_like(values)
    owner = np.full((n, p), -1)  # track id per node and slot
    held = np.full((n, p), -np.inf)  # depth of the patch in each slot and node
    tracks = []  # per track id: [surface, slot, last key, key before, last node] (_key)
    for i in range(n):
        newcomers = []
        for surface in sorted(set(surfaces)):
            alive = sorted((t for t, track in enumerate(tracks)
                            if track[0] == surface and track[4] == i - 1),
                           key=lambda t: tracks[t][2][0])
            mine = sorted((k for k in np.flatnonzero(found[i]) if surfaces[k] == surface),
                          key=lambda k: values[i, k, _WHERE])

            def cost(a, b):
                _, _, last, before, _ = tracks[alive[a]]
                guesses = [last] if before is None else [last, 2.0 * last - before]
                return min(_distance(g, _key(values[i, mine[b]], depth[i, mine[b]]))
                           for g in guesses)

            pairs = _pair(alive, mine, cost, _TRACK_JUMP)
            for a, b in pairs:
                t, k = alive[a], mine[b]
                track = tracks[t]
                track[2], track[3], track[4] = _key(values[i, k], depth[i, k]), track[2], i
                owner[i, track[1]], out[i, track[1]] = t, values[i, k]
                held[i, track[1]] = depth[i, k]
            paired = {mine[b] for _, b in pairs}
            newcomers += [k for k in mine if k not in paired]
        for k in sorted(newcomers, key=lambda k: -depth[i, k]):  # deepest first
            surface = surfaces[k]
            free = [j for j in range(p) if surfaces[j] == surface
                    and owner[i, j] < 0 and (i == 0 or owner[i - 1, j] < 0)]
            if not free:
                # more patches than slots: the shallowest patch gives up its slot
                taken = [j for j in range(p) if surfaces[j] == surface and owner[i, j] >= 0]
                j = min(taken, key=lambda j: held[i, j]) if taken else None
                if j is None or held[i, j] >= depth[i, k]:
                    continue
                tracks[owner[i, j]][4] = -1  # that track ends here
                free = [j]
            tracks.append([surface, free[0], _key(values[i, k], depth[i, k]), None, i])
            owner[i, free[0]] = len(tracks) - 1
            out[i, free[0]] = values[i, k]
            held[i, free[0]] = depth[i, k]
    out[:, np.all(owner < 0, axis=0), 0] = -_CLEAR  # slots that never hold a patch
    return _continue_empty(out, owner, heights), owner >= 0


def _continue_empty(values, owner, heights):
    """``values`` (L, P, F) of one lateral line with each slot's entries where it holds
    no patch (``owner`` (L, P): an id per patch, -1 for none) continued from the nearest
    node where it does: that patch's geometry, and its depth (at each node's own
    ``heights`` (L,) [m]: the wheel's height changes from node to node) falling off as
    :func:`_fall` says, so that the slot's depth along the line has no kink for the
    spline to ring at where a patch is born or dies (a birth from a shoulder starts at
    zero depth). A slot that holds no patch anywhere on the line is left as it is."""
    out = values.copy()
    for j in range(values.shape[1]):
        have = np.flatnonzero(owner[:, j] >= 0)
        if have.size == 0:
            continue
        depth = values[:, j, 0] - values[:, j, 1] * heights
        for i in np.flatnonzero(owner[:, j] < 0):
            near = have[np.argmin(np.abs(have - i))]
            inner = near - 1 if i > near else near + 1
            trend = 0.0
            if 0 <= inner < len(depth) and owner[inner, j] == owner[near, j]:
                trend = depth[inner] - depth[near]
            fall = min(_CLEAR, _fall(trend, depth[near]) * abs(i - near))
            out[i, j] = values[near, j]
            out[i, j, 0] += values[near, j, 1] * (heights[i] - heights[near]) - fall
    return out


def _runs(owned):
    """An id per run of consecutive nodes (axis 0) where a slot holds a patch, -1
    elsewhere: (L, P) from ``owned`` (L, P)."""
    starts = owned & ~np.concatenate([np.zeros_like(owned[:1]), owned[:-1]])
    return np.where(owned, np.cumsum(starts, axis=0), -1)


def _fall(trend, depth):
    """How fast [m per node] a slot's depth falls beyond the last node whose patch it
    held, of ``depth`` [m] there: the patch's own ``trend`` [m per node] toward that
    node (a continued line has no kink for the spline to ring at) between ``_RAMP_MIN``
    and ``_RAMP``, and at least ``depth`` (a gone patch is clear of the rail from the
    next node on)."""
    return max(float(np.clip(trend, _RAMP_MIN, _RAMP)), float(depth))


def _match(found, values, depth, reference, owned, surfaces, rigid, height, reference_height):
    """Values (P, F) of a node in the slots of an already assigned neighbour
    (``reference`` (P, F), ``owned`` (P,)): each surface's patches paired in order along
    the wheel with the neighbour's owned slots (:func:`_pair`, as many pairs as there
    can be, then the nearest), a newcomer to a free slot. A slot left empty keeps the
    neighbour's values: as they are when ``rigid`` (the next deeper approach level: its
    depth offset and slope continue the patch as the wheel rises), else with the
    neighbour's depth (the wheel's vertical position is ``height`` [m] here,
    ``reference_height`` there), clear of the rail by at least one ramp step
    (``_RAMP``) where the neighbour held a patch. Returns the values and the owned
    flags."""
    out, taken = reference.copy(), np.zeros(len(owned), dtype=bool)
    # the neighbour's depths: its patches' lines continued to this height when rigid
    reference_depth = reference[:, 0] - reference[:, 1] * (height if rigid else reference_height)
    for surface in sorted(set(surfaces)):
        slots = sorted((j for j in range(len(owned)) if surfaces[j] == surface and owned[j]),
                       key=lambda j: reference[j, _WHERE])
        mine = sorted((k for k in np.flatnonzero(found) if surfaces[k] == surface),
                      key=lambda k: values[k, _WHERE])

        def cost(a, b):
            j, k = slots[a], mine[b]
            return _distance(_key(reference[j], reference_depth[j]), _key(values[k], depth[k]))

        pairs = _pair(slots, mine, cost, _MATCH_LIMIT)
        for a, b in pairs:
            out[slots[a]], taken[slots[a]] = values[mine[b]], True
        paired = {mine[b] for _, b in pairs}
        free = [j for j in range(len(owned)) if surfaces[j] == surface and not owned[j]]
        for k in sorted((k for k in mine if k not in paired), key=lambda k: -depth[k]):
            if free:
                j = free.pop(0)
                out[j], taken[j] = values[k], True
    if not rigid:
        out[~taken, 0] += out[~taken, 1] * (height - reference_height)
        gone = ~taken & owned
        out[gone, 0] -= np.maximum(_RAMP, reference_depth[gone])
        return out, taken
    return out, owned | taken


def _assign_slots(found, values, depth, heights, surfaces):
    """Slot-consistent values (L, Y, R, A, P, F) of a whole grid (lateral, yaw, roll,
    approach): patches tracked along the lateral axis on the central yaw and roll line
    at the deepest approach, then every other node matched to its neighbour toward that
    line (shallower levels to the deeper one, then outward in yaw, then in roll); last,
    on every lateral line, the empty slots continued from their nearest patch
    (:func:`_continue_empty`)."""
    n_lat, n_yaw, n_roll, n_app = found.shape[:4]
    out = np.empty_like(values)
    owned = np.zeros(found.shape, dtype=bool)
    jc, kc, deep = n_yaw // 2, n_roll // 2, n_app - 1

    def match(i, j, k, m, ref, rigid):
        out[i, j, k, m], owned[i, j, k, m] = _match(
            found[i, j, k, m], values[i, j, k, m], depth[i, j, k, m], out[(i,) + ref],
            owned[(i,) + ref], surfaces, rigid, heights[i, j, k, m], heights[(i,) + ref])

    out[:, jc, kc, deep], owned[:, jc, kc, deep] = _track_line(
        found[:, jc, kc, deep], values[:, jc, kc, deep], depth[:, jc, kc, deep], surfaces,
        heights[:, jc, kc, deep])
    outward = lambda centre, count: [x for x in sorted(range(count), key=lambda x: abs(x - centre))  # noqa: E731
                                     if x != centre]
    for i in range(n_lat):
        for m in range(deep - 1, -1, -1):
            match(i, jc, kc, m, (jc, kc, m + 1), True)
        for j in outward(jc, n_yaw):
            toward = j - 1 if j > jc else j + 1
            for m in range(n_app):
                match(i, j, kc, m, (toward, kc, m), False)
        for k in outward(kc, n_roll):
            toward = k - 1 if k > kc else k + 1
            for j in range(n_yaw):
                for m in range(n_app):
                    match(i, j, k, m, (j, toward, m), False)
    # every other line's empty slots continued along the lateral axis as the central one's
    for j in range(n_yaw):
        for k in range(n_roll):
            for m in range(n_app):
                if (j, k, m) != (jc, kc, deep):
                    out[:, j, k, m] = _continue_empty(out[:, j, k, m], _runs(owned[:, j, k, m]),
                                                      heights[:, j, k, m])
    return out


def _limit_rates(values, heights):
    """``values`` (L, Y, R, A, P, F) with each geometry rate no larger than three times
    the field's change per metre of height to either neighbouring level (the
    Fritsch-Carlson bound: the Hermite interpolation between two levels then does not
    overshoot them; ``heights`` (L, Y, R, A) [m]). The search's rates are exact but
    unbounded where a patch is born (the centre of a vanishing interpenetration moves
    without limit) or its deepest point lies on a flat top; they bound the others only
    where the field is flat or turns between levels."""
    # how far the wheel comes down from each level to the next [m]
    drop = np.maximum(heights[..., :-1] - heights[..., 1:], 1e-12)[..., None, None]
    secant = np.abs(np.diff(values[..., _VALUES], axis=3)) / drop
    bound = np.full(secant.shape[:3] + (secant.shape[3] + 1,) + secant.shape[4:], np.inf)
    bound[..., :-1, :, :] = secant
    bound[..., 1:, :, :] = np.minimum(bound[..., 1:, :, :], secant)
    out = values.copy()
    out[..., _RATES] = np.clip(values[..., _RATES], -3.0 * bound, 3.0 * bound)
    return out
