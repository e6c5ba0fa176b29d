"""The vertical load path of a vehicle at rest: which bodies rest on which, whether every
body rests on the wheelsets, and the static loads the elements marked
``preload = "static"`` carry at zero deflection.

**Support.** Every body must be joined to a wheelset (or to the fixed frame, "ground")
by a chain of joints and force elements; one that is not is free to fall, and the
vehicle's equations are singular at rest.

**Levels.** Over the joints and the static elements only, a body's level is its
distance in links from the nearest wheelset or the ground (wheelset 0, axlebox 1,
bogie frame 2, carbody 3 in the trailer). A static element joins two bodies of
different levels: the upper one rests on it.

**Loads, top down.** Bodies are taken from the highest level down. Each body's load is
its weight at its centre of mass plus the loads of the elements and joints it carries,
at their points. It is shared among the body's supports (its static elements to lower
bodies and its joints to lower bodies): equally if equal shares balance the vertical
force and the moments about x and y (any left-right and fore-aft symmetric layout,
exactly: the trailer's m_c g / 4 and (m_c + 2 m_b) g / 8), otherwise by the
minimum-norm shares that balance the force and both moments (least squares when the
supports cannot balance them all, e.g. all on one line). A share through a joint needs
no preload: the joint's reaction carries it down to the lower body.
"""

import numpy as np

from .quantities import file_error

BALANCE_TOLERANCE = 1e-9  # relative moment residual below which equal shares balance


def _graph(model, links):
    neighbours = {b.name: set() for b in model.bodies} | {"ground": set()}
    for link in links:
        neighbours[link.body_i].add(link.body_j)
        neighbours[link.body_j].add(link.body_i)
    return neighbours


def _levels(model, links):
    neighbours = _graph(model, links)
    level = {w.body: 0 for w in model.wheelsets} | {"ground": 0}
    frontier = list(level)
    while frontier:
        following = []
        for name in frontier:
            for other in sorted(neighbours[name]):
                if other not in level:
                    level[other] = level[name] + 1
                    following.append(other)
        frontier = following
    return level


def check_supported(model) -> None:
    """ValueError naming the first body that no chain of joints and elements joins to a
    wheelset or the ground."""
    if not model.wheelsets:
        raise file_error(model.where, "top level", "wheelset", "the vehicle has no "
                         "wheelset (declare one with [[wheelset]] or in a template)")
    level = _levels(model, model.joints + model.elements)
    for body in model.bodies:
        if body.name not in level:
            raise file_error(model.where, body.table, "name", f"nothing supports body "
                             f"{body.name!r}: no chain of joints or elements joins it to a "
                             f"wheelset, so the vehicle is singular at rest")


def _point_on(link, name):
    return link.at_i if link.body_i == name else link.at_j


def _shares(loads, supports):
    """Shares (n,) [kg] of the total of ``loads`` [(mass, x, y)] carried by supports at
    ``supports`` [(x, y)] (module docstring)."""
    total = 0.0
    for mass, _, _ in loads:
        total += mass
    n = len(supports)
    equal = np.full(n, total / n)
    xy = np.array(supports, dtype=np.float64).reshape(n, 2)
    moment = np.array([sum(m * x for m, x, _ in loads), sum(m * y for m, _, y in loads)])
    scale = abs(total) * (1.0 + np.abs(xy).max())
    if np.all(np.abs(equal @ xy - moment) <= BALANCE_TOLERANCE * scale):
        return [total / n] * n
    a = np.vstack([np.ones(n), xy.T])
    return np.linalg.lstsq(a, np.concatenate([[total], moment]), rcond=None)[0].tolist()


def static_loads(model, gravity: float) -> dict[str, tuple[float, bool]]:
    """``{element name: (load [N], upper_is_j)}`` for the elements marked
    ``preload = "static"``: the vertical load each carries at rest and whether its
    body j is the upper one. ValueError for a static element whose bodies do not rest
    on the wheelsets through joints and static elements, or that lie at one level."""
    static = [e for e in model.elements if e.static]
    level = _levels(model, model.joints + tuple(static))
    upper = {}
    for e in static:
        li, lj = level.get(e.body_i), level.get(e.body_j)
        if li is None or lj is None or li == lj:
            raise file_error(model.where, e.table, "preload", f'"static": cannot tell which '
                             f'of {e.body_i!r} and {e.body_j!r} rests on the other (each '
                             f'must rest on a wheelset through joints and static elements, '
                             f'at different distances from it)')
        upper[e.name] = e.body_j if lj > li else e.body_i
    joints = [j for j in model.joints if level.get(j.body_i) != level.get(j.body_j)
              and None not in (level.get(j.body_i), level.get(j.body_j))]
    joint_upper = {j.name: max((j.body_i, j.body_j), key=level.get) for j in joints}
    share = {}  # id of an element or joint -> mass [kg] it carries
    bodies = sorted(model.bodies, key=lambda b: -level.get(b.name, -1))
    for body in bodies:
        if level.get(body.name, 0) == 0:
            continue
        name = body.name
        loads = [(body.mass, body.position[0], body.position[1])]
        carried = [e for e in static if name in (e.body_i, e.body_j) and upper[e.name] != name]
        carried += [j for j in joints if name in (j.body_i, j.body_j)
                    and joint_upper[j.name] != name]
        loads += [(share[id(c)], *_point_on(c, name)[:2]) for c in carried]
        supports = [e for e in static if upper[e.name] == name]
        supports += [j for j in joints if joint_upper[j.name] == name]
        if not supports:
            continue
        for link, s in zip(supports, _shares(loads, [_point_on(k, name)[:2]
                                                     for k in supports])):
            share[id(link)] = s
    return {e.name: (share[id(e)] * gravity, upper[e.name] == e.body_j) for e in static}
