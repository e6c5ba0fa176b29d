"""The rail under a wheel: the one place that defines where each rail is.

A rail's profile origin and frame at arc length ``s`` are made of

1. the design track's frame ``[t n b]`` at ``s`` (:func:`jaxrail.track.track_frame`);
2. the rail's lateral offset from the track centre along ``n``, ``side *
   track.rails.offset`` (:class:`Rails`: the rails' profile and the offset that sets the
   gauge, :func:`jaxrail.profiles.rail_offset`);
3. the track's irregularity, when it has one (:attr:`Track.irregularity`,
   :mod:`jaxrail.track.irregularity`): the rail moved by ``y = a + side g / 2`` along
   ``n`` and ``z = v + side c / 2`` along ``b``;
4. on a flexible track, the rail's deflection under the wheelset being evaluated, an
   argument ``deflection`` (lateral, vertical) [m] of the functions below (the flexible
   track's state, :mod:`jaxrail.track.flexible`, not kept on the track), along the same
   ``n`` and ``b``.

The contact search, the contact tables, the loads, the initial equilibrium and the
outputs (a wheel's height over its rail, :func:`wheel_height`) all find a wheel's rail
through :func:`rail_under_wheel` and :func:`rail_frame`. A wheel's origin on its axle
is the taping point's plane, :data:`HALF_TAPING_DISTANCE` from the wheelset centre
(:func:`wheel_origin`).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from ..profiles import Profile, gauge_point, rail_offset, uic60
from .geometry import _cant_cos_sin, _side_sign, centreline_and_frame, frame_from_cos_sin
from .projection import project_onto_centreline

HALF_TAPING_DISTANCE = 0.75  # [m] taping lines 1500 mm apart (back-to-back 1360 mm)
STANDARD_GAUGE = 1.435  # [m]
STANDARD_INCLINATION = "1:40"  # of the standard UIC60 rail
# a scenario's [track] keys that make the rails (jaxrail.scenarios): a vehicle file or a
# scenario's [vehicle] that gives one is refused, the rails being the track's
RAIL_KEYS = ("rail", "inclination", "gauge")


class Rails(eqx.Module):
    """The track's two rails: their cross-section and where they stand (traced: changing
    them never recompiles, and both can be batched or differentiated).

    Fields:
        profile: the rail :class:`~jaxrail.profiles.Profile` of both rails, lateral
            coordinate toward the field side; the right rail's is its mirror image.
        offset: distance [m] from the track centre to each rail's profile origin along
            the canted track frame's ``n`` (float64 scalar), which sets the gauge
            (:func:`jaxrail.profiles.rail_offset`; 0.75303 m for UIC60 1:40 at 1.435 m).
    """

    profile: Profile
    offset: Float[Array, ""] = eqx.field(converter=lambda x: jnp.asarray(x, jnp.float64))

    @classmethod
    def at_gauge(cls, profile: Profile, gauge: Float[ArrayLike, ""] = STANDARD_GAUGE
                 ) -> "Rails":
        """Rails of ``profile`` whose gauge points (14 mm below the rail tops) are
        ``gauge`` [m] apart."""
        return cls(profile, rail_offset(profile, gauge))

    @property
    def gauge(self) -> Float[Array, ""]:
        """Distance [m] between the rails' gauge points, 14 mm below their tops."""
        return 2.0 * (self.offset + gauge_point(self.profile))


_STANDARD: list[Rails] = []  # the standard rails once computed outside any trace


def standard_rails() -> Rails:
    """UIC60 inclined 1:40 at standard gauge (1.435 m): the rails of every track unless
    it is given others (:meth:`jaxrail.track.Track.with_rails`). Computed once and kept
    when first asked for outside a trace (inside one the offset is traced, and not kept)."""
    if not _STANDARD:
        with jax.ensure_compile_time_eval():  # the profile's static domain needs values
            profile = uic60(STANDARD_INCLINATION)
        rails = Rails.at_gauge(profile, STANDARD_GAUGE)
        if isinstance(rails.offset, jax.core.Tracer):
            return rails
        _STANDARD.append(rails)
    return _STANDARD[0]


def wheel_origin(wheelset_position, wheelset_rotation, side) -> Float[Array, "3"]:
    """Origin [m] of the ``side`` wheel's profile (+1 left, -1 right): the wheelset
    centre (3,) moved :data:`HALF_TAPING_DISTANCE` along the axle (the second column
    of ``wheelset_rotation`` (3, 3)), global."""
    return wheelset_position + side * HALF_TAPING_DISTANCE * wheelset_rotation[:, 1]


def rail_displacement(track, s, side, deflection=None
                      ) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """``(lateral, vertical)`` [m] of the ``side`` rail from its design place at ``s``
    [m], along the canted track frame's ``n`` and ``b``: the irregularity's (zeros on an
    ideal track) plus, on a flexible track, ``deflection`` (2,) [m], this rail's
    (lateral, vertical) deflection under the wheelset being evaluated
    (:mod:`jaxrail.track.flexible`; None: a rigid rail)."""
    zero = jnp.zeros((), dtype=jnp.float64)
    lateral, vertical = zero, zero
    if getattr(track, "irregularity", None) is not None:
        lateral, vertical = track.irregularity.rail_displacement(s, side)
    if deflection is not None:
        lateral, vertical = lateral + deflection[0], vertical + deflection[1]
    return lateral, vertical


def rail_frame(
    track, s: Float[ArrayLike, ""], side, deflection: Float[ArrayLike, "2"] | None = None,
) -> tuple[Float[Array, "3"], Float[Array, "3 3"]]:
    """Rail profile origin and orientation at ``s`` (paper eq. 1).

    **Arguments:**
        track: the track (design layout, its :class:`Rails` and, optionally, its
            irregularity).
        s: arc length along the centreline [m].
        side: ``+1`` or ``"left"`` for the left rail, ``-1`` or ``"right"`` for the right
            (a traced array of +-1 is accepted for vmapping over both rails).
        deflection: on a flexible track, this rail's (lateral, vertical) deflection
            (2,) [m] under the wheelset being evaluated; None: a rigid rail.

    **Returns:** ``(origin, A)``: ``origin = centreline + (side * offset + y) n + z b``
    [m], global frame, shape ``(3,)``, with ``offset`` the rails' (:attr:`Rails.offset`,
    along the canted ``n``) and ``(y, z)`` the irregularity's displacement of this rail
    plus its deflection (:func:`rail_displacement`); ``A = [t n b]`` ``(3, 3)``, the
    design track frame, the same for both rails (the right rail's field-side mirroring
    is applied to profile coordinates by :func:`jaxrail.track.rail_point` and by the
    contact search via ``side``).
    """
    return _rail_on_centreline(track, s, *centreline_and_frame(track, s), side, deflection)


def _rail_on_centreline(track, s, centre, frame, side, deflection=None):
    """:func:`rail_frame` from the centreline point ``centre`` (3,) [m] and track frame
    ``frame`` (3, 3) at ``s`` [m]."""
    sign = _side_sign(side)
    offset = track.rails.offset
    lateral, vertical = rail_displacement(track, s, sign, deflection)
    origin = (centre + (sign * offset + lateral) * frame[:, 1]
              + vertical * frame[:, 2])
    return origin, frame


def rail_point(
    track,
    s: Float[ArrayLike, ""],
    side,
    u: Float[ArrayLike, ""],
    f: Float[ArrayLike, ""],
    dx: Float[ArrayLike, ""] = 0.0,
    deflection: Float[ArrayLike, "2"] | None = None,
) -> Float[Array, "3"]:
    """A point of a rail surface, global frame [m] (paper eq. 2).

    ``origin + A @ (dx, side * u, f)`` with ``(origin, A) = rail_frame(...)``.

    **Arguments:** as :func:`rail_frame`, plus
        u: lateral profile coordinate [m], positive toward the **field side** (away
            from the track centre); mirrored onto the track's ``n`` by ``side``, so the
            same profile serves both rails.
        f: profile height [m] along the canted ``b``.
        dx: longitudinal offset [m] along ``t`` (the rail is locally straight).
    """
    sign = _side_sign(side)
    origin, frame = rail_frame(track, s, sign, deflection)
    local = jnp.stack(
        [
            jnp.asarray(dx, dtype=jnp.float64),
            sign * jnp.asarray(u, dtype=jnp.float64),
            jnp.asarray(f, dtype=jnp.float64),
        ]
    )
    return origin + frame @ local


def rail_under_wheel(track, origin, side, s_guess=None, deflection=None, iterations=2):
    """The rail section under a wheel whose profile origin is ``origin`` (3,) [m]
    (:func:`wheel_origin`): ``(s_rail, rail_origin (3,), rail_axes (3, 3))``, the
    section's arc length [m] (eqs. 3-5: the design centreline's normal plane through
    the wheel origin) and the rail's frame there (:func:`rail_frame`), the rail moved by
    its irregularity and, on a flexible track, by ``deflection`` (2,) [m] (lateral,
    vertical) under this wheel; ``s_guess`` and ``iterations``: as
    :func:`~jaxrail.track.projection.project_onto_centreline`'s."""
    s_rail, centre, tangent = project_onto_centreline(track, origin, s_guess, iterations)
    frame = frame_from_cos_sin(tangent, _cant_cos_sin(track, s_rail))
    rail_origin, rail_axes = _rail_on_centreline(track, s_rail, centre, frame, side, deflection)
    return s_rail, rail_origin, rail_axes


def lateral_from_centre(track, s, side, y_rail, deflection=None):
    """Lateral position [m] from the design track centre (along the canted ``n``,
    positive left) of the point ``y_rail`` [m] (toward the field side) of the ``side``
    rail's profile at ``s`` [m], with the rail's irregularity and ``deflection`` (2,)
    [m] (:func:`rail_displacement`)."""
    return (side * (track.rails.offset + y_rail)
            + rail_displacement(track, s, side, deflection)[0])


def wheel_height(track, wheelset_position, wheelset_rotation, side, deflection=None,
                 s_guess=None):
    """Height [m] of the ``side`` wheel's profile origin (:func:`wheel_origin`) over its
    rail's profile origin, along the rail's ``b`` (:func:`rail_under_wheel`: with the
    rail's irregularity and ``deflection`` (2,) [m]). ``s_guess`` [m]: the wheelset's
    arc length, from which one Newton step and the last reach the wheel's section (the
    wheel is at most centimetres along the track from the wheelset's centre: the last
    step moves it by well under 1e-6 m, ``tests/track/test_rails.py``); None: from
    the nearest sample (:func:`~jaxrail.track.projection.project_onto_centreline`)."""
    origin = wheel_origin(wheelset_position, wheelset_rotation, side)
    iterations = 2 if s_guess is None else 1
    _, rail_origin, rail_axes = rail_under_wheel(track, origin, side, s_guess, deflection,
                                                 iterations)
    return (origin - rail_origin) @ rail_axes[:, 2]


def track_irregularity(track, s) -> Float[Array, "4"]:
    """The four irregularity channels [m] at ``s`` [m] (:data:`.irregularity.CHANNELS`),
    zeros on an ideal track."""
    if getattr(track, "irregularity", None) is None:
        return jnp.zeros(4, dtype=jnp.float64)
    return track.irregularity.at(s)
