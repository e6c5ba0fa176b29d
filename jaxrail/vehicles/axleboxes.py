"""Wheelsets that carry their axleboxes: the joint-free form of a vehicle file.

A vehicle file models an axlebox as a body on a revolute joint about its wheelset's
axle (five rows of eq. 19 per axle). Where the topology allows it,
:func:`carry_axleboxes` folds each axlebox body into its wheelset instead: the
wheelset becomes an axle body (:mod:`jaxrail.multibody.axle_frame`) whose force
elements attach to its non-spinning axle frame, and the axle joints disappear. A
vehicle whose joints were all axle joints then has no constraint but the Euler
parameters' normalisation, a block-diagonal mass matrix and no Schur complement.

What folding keeps and drops:
- the axlebox's mass, and its roll and yaw inertia, join the wheelset's (so the
  axlebox's inertia must be the same about x and z: the wheelset spins under it);
- its pitch about the axle goes: in the joint form only the elements' rotational
  stiffness about the axle holds it, nothing else restrains it, so those carry no
  moment at rest and are dropped (a bushing's y components, the axle's axis);
- every element keeps its points (vehicle frame), now on the axle frame.

Folding is refused (the file keeps its joints, ``reason`` says why) where it would
change the model beyond that: an axlebox centre off its wheelset's, an inertia
with products of inertia (the axlebox's or the wheelset's), a joint that is
not one revolute joint about the axle through the centres, an element point off the
axle line (a moment about it), an element kind that applies moments other than a
bushing's, a bushing whose frame does not have the axle as its y axis, or an element
on the wheelset itself (it would stop spinning with it).
"""

import dataclasses

import numpy as np

from .vehicle_model import VehicleModel

POINT_FORCE_KINDS = ("spring_damper", "bump_stop", "table_spring", "friction_damper",
                     "traction_rod", "maxwell_damper")
"""Element kinds whose loads are forces at their two points only: on the axle line,
they apply no moment about the axle."""
AXLE = np.array([0.0, 1.0, 0.0])
_TOLERANCE = 1e-9  # [m], [-]: points and axes that coincide


@dataclasses.dataclass(frozen=True)
class Folded:
    """The outcome of :func:`carry_axleboxes`: the model (folded, or as given), the
    names of its axle bodies (empty if not folded) and, if not folded, why."""

    model: VehicleModel
    axle_bodies: tuple[str, ...]
    reason: str = ""


def _close(a, b):
    return np.allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float),
                       atol=_TOLERANCE, rtol=0.0)


def _parallel_to_axle(axis) -> bool:
    a = np.asarray(axis, dtype=float)
    return _close(np.abs(a / np.linalg.norm(a)), AXLE)


def _check_joint(joints, wheelset, box, centre):
    mine = [j for j in joints if box.name in (j.body_i, j.body_j)]
    if len(mine) != 1 or {mine[0].body_i, mine[0].body_j} != {wheelset.body, box.name}:
        return f"axlebox {box.name!r} has joints other than one to {wheelset.body!r}"
    joint = mine[0]
    if joint.kind != "revolute":
        return f"joint {joint.name!r} is a {joint.kind} joint, not a revolute one"
    axes = [joint.values.get(k, (0.0, 0.0, 1.0)) for k in ("axis_i", "axis_j")]
    if not all(_parallel_to_axle(a) for a in axes):
        return f"joint {joint.name!r} does not turn about the axle (y)"
    if not (_close(joint.at_i, centre) and _close(joint.at_j, centre)):
        return f"joint {joint.name!r} is not at the wheelset's centre"
    return ""


def _principal(body):
    """The principal moments (3,) [kg m^2] of a body's inertia, or None if it is a
    tensor with products of inertia."""
    inertia = np.asarray(body.inertia, dtype=float)
    if inertia.shape == (3, 3):
        return np.diag(inertia) if _close(inertia, np.diag(np.diag(inertia))) else None
    return inertia


def _moved_element(link, box, wheelset, centre):
    """The element ``link`` of axlebox body ``box`` moved onto ``wheelset``'s axle frame,
    or a string saying why it cannot be."""
    side = "i" if link.body_i == box.name else "j"
    at = np.asarray(link.at_i if side == "i" else link.at_j, dtype=float)
    if not (_close(at[0], centre[0]) and _close(at[2], centre[2])):
        return f"element {link.name!r} is attached off the axle line"
    values = dict(link.values)
    if link.kind == "bushing":
        frame = values.get("frame_i")
        if frame is not None and not _close(np.abs(np.asarray(frame, dtype=float)[:, 1]), AXLE):
            return f"bushing {link.name!r}: its frame's y axis is not the axle"
        for key in ("stiffness", "damping", "preload"):
            if values.get(key) is not None:
                six = [float(v) for v in values[key]]
                six[4] = 0.0  # the rotation about the axle: the axlebox's dropped pitch
                values[key] = six
    elif link.kind not in POINT_FORCE_KINDS:
        return f"element {link.name!r} of kind {link.kind!r} applies moments"
    renamed = {"body_" + side: wheelset.body}
    return dataclasses.replace(link, values=values, **renamed)


def carry_axleboxes(model: VehicleModel) -> Folded:
    """The model with each wheelset carrying its axlebox body (module docstring), or
    the model as given and the reason where the topology does not allow it."""
    boxes = {w.body: w.axlebox for w in model.wheelsets if w.axlebox is not None}
    if not boxes:
        return Folded(model, (), "no wheelset names an axlebox body")
    bodies = {b.name: b for b in model.bodies}
    elements = list(model.elements)
    merged = dict(bodies)
    for wheelset in model.wheelsets:
        box = bodies[wheelset.axlebox]
        centre = np.asarray(bodies[wheelset.body].position, dtype=float)
        if not _close(box.position, centre):
            return Folded(model, (), f"axlebox {box.name!r} is not centred on its wheelset")
        reason = _check_joint(model.joints, wheelset, box, centre)
        if reason:
            return Folded(model, (), reason)
        inertia, own = _principal(box), bodies[wheelset.body]
        spin = _principal(own)
        if inertia is None or spin is None:
            return Folded(model, (), f"{box.name!r} or {own.name!r} has products of "
                                     f"inertia (not principal about the axle)")
        if not np.isclose(inertia[0], inertia[2], rtol=1e-12):
            return Folded(model, (), f"axlebox {box.name!r}: its inertia differs about x "
                                     f"and z (the wheelset spins under it)")
        if any(wheelset.body in (e.body_i, e.body_j) for e in model.elements):
            return Folded(model, (), f"an element acts on wheelset {wheelset.body!r} itself")
        for k, link in enumerate(elements):
            if box.name in (link.body_i, link.body_j):
                moved = _moved_element(link, box, wheelset, centre)
                if isinstance(moved, str):
                    return Folded(model, (), moved)
                elements[k] = moved
        merged[own.name] = dataclasses.replace(
            own, mass=own.mass + box.mass,
            inertia=[spin[0] + inertia[0], spin[1], spin[2] + inertia[2]])
        del merged[box.name]
    joints = tuple(j for j in model.joints
                   if not any(name in boxes.values() for name in (j.body_i, j.body_j)))
    folded = dataclasses.replace(
        model, bodies=tuple(merged[b.name] for b in model.bodies if b.name in merged),
        wheelsets=tuple(dataclasses.replace(w, axlebox=None) for w in model.wheelsets),
        joints=joints, elements=tuple(elements))
    return Folded(folded, tuple(boxes), "")
