"""A constrained multibody system: its structure and parameters, and their assembly.

Structure and parameters are separate (docs/design.md §2): `System` holds only static
topology (body count and names, and per joint or force kind the body indices of its
elements), so changing it recompiles; `SystemParams` holds every physical number as a
float64 array, so it can be batched (vmap) and differentiated. `build_system` makes
both from build-time descriptions (RigidBody, Revolute, Bushing, ...). The equations
of motion are in :mod:`jaxrail.multibody.equations`.
"""

import dataclasses

import equinox as eqx
import numpy as np
from jaxtyping import Array, Float

from jaxrail._float64 import require_float64

from . import bodies as bd
from . import forces as fc
from . import joints as jt
from ._values import checked_vector, float64_array, point_arrays


@dataclasses.dataclass(frozen=True)
class Group:
    """Static topology of the elements of one kind: body indices (-1 = ground)."""

    kind: str
    body_i: tuple[int, ...]
    body_j: tuple[int, ...]
    names: tuple[str, ...]


class System(eqx.Module):
    """Static structure of a multibody system (no array leaves; hashable).

    Fields: n_bodies; body_names; joint_groups and force_groups, one `Group` per kind
    present, in the order of joints.JOINT_KINDS and forces.FORCE_KINDS; axle_bodies:
    the bodies (wheelsets) whose force elements attach to their non-spinning axle
    frame (:mod:`.axle_frame`), sorted.
    """

    n_bodies: int = eqx.field(static=True)
    body_names: tuple[str, ...] = eqx.field(static=True)
    joint_groups: tuple[Group, ...] = eqx.field(static=True)
    force_groups: tuple[Group, ...] = eqx.field(static=True)
    axle_bodies: tuple[int, ...] = eqx.field(static=True, default=())

    @property
    def n_constraints(self) -> int:
        """Rows of Phi: one normalisation per body plus the joint equations."""
        rows = sum(jt.JOINT_KINDS[g.kind][0] * len(g.body_i) for g in self.joint_groups)
        return self.n_bodies + rows

    @property
    def jointless(self) -> bool:
        """Whether the system has no joints: its constraints are the bodies'
        normalisations, each on its own body's coordinates."""
        return not self.joint_groups

    def find(self, name: str) -> tuple[str, str, int]:
        """("body", "", i) or ("joint" | "force", kind, index within its kind)."""
        if name in self.body_names:
            return "body", "", self.body_names.index(name)
        kinds = (("joint", self.joint_groups), ("force", self.force_groups))
        for what, groups in kinds:
            for g in groups:
                if name in g.names:
                    return what, g.kind, g.names.index(name)
        raise ValueError(f"name {name!r} is not a body, joint or force element")


class SystemParams(eqx.Module):
    """Traced parameters: bodies, joints[kind], forces[kind], gravity (3,) [m/s^2]
    (global), Baumgarte alpha [1/s] and beta [1/s] (scalars)."""

    bodies: bd.BodyParams
    joints: dict
    forces: dict
    gravity: Float[Array, " 3"]
    baumgarte_alpha: Float[Array, ""]
    baumgarte_beta: Float[Array, ""]


def _body_index(ref, names, what):
    if isinstance(ref, str):
        if ref == "ground":
            return -1
        if ref not in names:
            raise ValueError(f"{what}: unknown body {ref!r}")
        return names.index(ref)
    if isinstance(ref, (int, np.integer)) and -1 <= int(ref) < len(names):
        return int(ref)
    raise ValueError(f"{what}: body must be a name, 'ground' or an index in [-1, "
                     f"{len(names)}), got {ref!r}")


def _resolve(element, names, what):
    bi = _body_index(element.body_i, names, f"{what} body_i")
    bj = _body_index(element.body_j, names, f"{what} body_j")
    if bi == bj:
        raise ValueError(f"{what}: body_i and body_j must differ, both are {bi}")
    checked_vector(element.point_i, (3,), f"{what} point_i")
    checked_vector(element.point_j, (3,), f"{what} point_j")
    return bi, bj


def _joint_params(specs):
    frames = [s.frames() for s in specs]
    return jt.JointParams(
        **point_arrays(specs),
        frame_i=float64_array([f[0] for f in frames]),
        frame_j=float64_array([f[1] for f in frames]),
    )


def _groups(elements, kinds, names, what):
    groups, by_kind = [], {}
    for e in elements:
        if getattr(e, "kind", None) not in kinds:
            raise ValueError(f"{what} kind must be one of {sorted(kinds)}, got "
                             f"{getattr(e, 'kind', None)!r} ({e!r})")
    for kind in kinds:
        specs = [e for e in elements if e.kind == kind]
        if not specs:
            continue
        idx = [_resolve(s, names, f"{what} {s.name or kind!r}") for s in specs]
        groups.append(Group(kind, tuple(i for i, _ in idx), tuple(j for _, j in idx),
                            tuple(s.name for s in specs)))
        by_kind[kind] = specs
    return tuple(groups), by_kind


def build_system(bodies, joints=(), forces=(), gravity=(0.0, 0.0, 0.0),
                 baumgarte=(10.0, 10.0), axle_bodies=()) -> tuple[System, SystemParams]:
    """(System, SystemParams) from build-time descriptions.

    Arguments:
        bodies: sequence of RigidBody (n >= 1); body index = position in it.
        joints: Spherical / Revolute / Prismatic / Fixed; bodies by name, index, or
            "ground" / -1 for the fixed global frame.
        forces: descriptions of any kind of forces.FORCE_KINDS (SpringDamper, Bushing,
            BumpStop, TableSpring, AntiRollBar, FrictionDamper, TractionRod,
            MaxwellDamper, AirSpring).
        gravity: (3,) [m/s^2], global; e.g. (0, 0, -9.81) with z up.
        baumgarte: (alpha, beta) [1/s], feedback gains of eq. (19).
        axle_bodies: bodies (names or indices) that spin about their y axis and whose
            force elements attach to their non-spinning axle frame instead
            (:mod:`.axle_frame`): wheelsets that carry their axleboxes.
    """
    require_float64("a multibody system")
    bodies = tuple(bodies)
    if not bodies or not all(isinstance(b, bd.RigidBody) for b in bodies):
        raise ValueError("bodies must be a non-empty sequence of RigidBody")
    names = tuple(b.name for b in bodies)
    if len(set(names)) != len(names) or "ground" in names:
        raise ValueError(f"bodies must have unique names other than 'ground': {names}")
    inertia = [b.inertia_tensor() for b in bodies]
    alpha, beta = checked_vector(baumgarte, (2,), "baumgarte")
    if alpha < 0.0 or beta < 0.0:
        raise ValueError(f"baumgarte gains must be >= 0, got {baumgarte}")
    joint_groups, joint_specs = _groups(tuple(joints), jt.JOINT_KINDS, names, "joint")
    force_groups, force_specs = _groups(tuple(forces), fc.FORCE_KINDS, names, "force")
    axles = tuple(sorted({_body_index(b, names, "axle_bodies") for b in axle_bodies}))
    if -1 in axles:
        raise ValueError("axle_bodies: the ground has no axle")
    system = System(len(bodies), names, joint_groups, force_groups, axles)
    params = SystemParams(
        bodies=bd.BodyParams(float64_array([b.mass for b in bodies]), float64_array(inertia)),
        joints={k: _joint_params(s) for k, s in joint_specs.items()},
        forces={k: fc.FORCE_KINDS[k].params(s, f"force {k}") for k, s in force_specs.items()},
        gravity=float64_array(checked_vector(gravity, (3,), "gravity")),
        baumgarte_alpha=float64_array(alpha),
        baumgarte_beta=float64_array(beta),
    )
    return system, params


def stateful_groups(system: System) -> tuple[Group, ...]:
    """The force groups whose kind has internal states (``State.elements``' keys)."""
    return tuple(g for g in system.force_groups if fc.FORCE_KINDS[g.kind].states > 0)


def _element_states(system, elements, kind):
    """The internal states (k, r) of ``kind``'s elements, or None for a stateless kind
    (ValueError if a stateful kind's are missing)."""
    if fc.FORCE_KINDS[kind].states == 0:
        return None
    if elements is None or kind not in elements:
        raise ValueError(f"the {kind} elements have internal states: pass them "
                         f"(State.elements[{kind!r}], :func:`initial_element_states`)")
    return elements[kind]
