"""The contact search and the contact table on an irregular track: a harmonic
irregularity in all four channels moves each rail exactly as prescribed, i.e. each
wheel's contact equals that of the same wheel on the ideal track with the wheelset
moved the other way by its rail's displacement (y = a +- g/2, z = v +- c/2), computed
here from the harmonics themselves, not from the track's samples."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxrail.contact import search_wheelset, wheelset_pose
from jaxrail.contact.table import Axis, TableGrid, build_contact_table, table_patches
from jaxrail.profiles import s1002, uic60
from jaxrail.track import Irregularity, Rails, straight_track, track_frame

LENGTH = 100.0
STEP = 0.01  # [m] samples of the harmonics (the interpolation is then exact to 1e-10 m)
# amplitude [m], wavelength [m], phase [rad] of alignment, vertical, cross level, gauge
HARMONICS = ((2.0e-3, 13.0, 0.3), (1.0e-3, 21.0, 1.1), (0.1e-3, 17.0, -0.4),
             (0.8e-3, 9.0, 2.0))
STATIONS = (31.3, 44.0, 52.7, 61.9, 70.2)
TOLERANCE = 1e-6  # [m] contact positions on the profiles
GRID = TableGrid(lateral=Axis.span(-0.006, 0.006, 1.0e-4), yaw=Axis.span(0.0, 0.0, 1.0),
                 roll=Axis.span(0.0, 0.0, 1.0))


def harmonics(s):
    """The four channels [m] at ``s`` [m], exactly."""
    return np.array([a * np.cos(2 * np.pi * s / wavelength + phase)
                     for a, wavelength, phase in HARMONICS])


@pytest.fixture(scope="module")
def setup():
    wheel, rails = s1002(), Rails.at_gauge(uic60("1:40"), 1.435)
    s = np.arange(0.0, LENGTH + STEP / 2, STEP)
    ideal = straight_track(LENGTH, rails=rails)
    irregular = ideal.with_irregularity(Irregularity(harmonics(s).T, 0.0, STEP))
    return wheel, rails, ideal, irregular


def _poses(track, lateral, vertical):
    """Wheelset poses at :data:`STATIONS` on ``track``, shifted ``lateral`` [m] and at
    ``vertical`` [m] (arrays over the stations), no yaw or roll."""
    return jax.vmap(lambda s, y, z: wheelset_pose(track, s, y, z))(
        jnp.asarray(STATIONS), jnp.asarray(lateral), jnp.asarray(vertical))


def _cases(ideal):
    """The irregular case's poses (the wheelset follows the alignment and level, 1 mm to
    the left) and, per side, the ideal track's poses with the wheelset moved by minus
    that rail's displacement."""
    a, v, c, g = harmonics(np.asarray(STATIONS))
    lateral, vertical = a + 1.0e-3, v + 0.45977
    out = {}
    for index, side in enumerate((1.0, -1.0)):
        y, z = a + side * g / 2, v + side * c / 2
        out[index] = (lateral - y, vertical - z)
    return (lateral, vertical), out


def _compare(patch_fn, setup):
    _, _, ideal, irregular = setup
    (lateral, vertical), shifted = _cases(ideal)
    on_irregular = jax.vmap(lambda p, r: patch_fn(irregular, p, r))(*_poses(irregular, lateral,
                                                                             vertical))
    for index in (0, 1):
        reference = jax.vmap(lambda p, r: patch_fn(ideal, p, r))(*_poses(ideal, *shifted[index]))
        active = np.asarray(reference.active)[:, index]
        assert active.sum() >= len(STATIONS)  # every wheel touches its rail
        np.testing.assert_array_equal(np.asarray(on_irregular.active)[:, index], active)
        for field in ("y_wheel", "y_rail", "penetration", "rolling_radius"):
            got = np.asarray(getattr(on_irregular, field))[:, index][active]
            want = np.asarray(getattr(reference, field))[:, index][active]
            assert np.abs(got - want).max() < TOLERANCE, (field, index, np.abs(got - want).max())
        # the contact point in space moves with the rail: by the displacement along n, b
        a, v, c, g = harmonics(np.asarray(STATIONS))
        side = 1.0 - 2.0 * index
        frames = jax.vmap(lambda s: track_frame(ideal, s))(jnp.asarray(STATIONS))
        moved = np.asarray(on_irregular.rail_point)[:, index] - np.asarray(
            reference.rail_point)[:, index]
        expected = ((a + side * g / 2)[:, None, None] * np.asarray(frames)[:, None, :, 1]
                    + (v + side * c / 2)[:, None, None] * np.asarray(frames)[:, None, :, 2])
        # the reference wheelset was moved by the rail's displacement's opposite: its
        # contact point moved with it, so the irregular one lies the displacement away
        assert np.abs(moved - expected)[active].max() < TOLERANCE


def test_online_search_sees_the_displaced_rails(setup):
    wheel, _, _, _ = setup
    search = jax.jit(lambda track, p, r: search_wheelset(wheel, track, p, r))
    _compare(search, setup)


def test_table_lookup_sees_the_displaced_rails_without_a_rebuild(setup):
    wheel, rails, _, _ = setup
    table, _ = build_contact_table(wheel, rails, grid=GRID)

    @jax.jit
    def lookup(track, p, r):
        return jax.vmap(lambda side: table_patches(table, wheel, track, p, r, side))(
            jnp.array([1.0, -1.0]))

    _compare(lookup, setup)


def test_search_gradient_in_the_amplitude_matches_central_differences(setup):
    """d(penetration, contact position) / d(scale) through the search, against central
    differences, and finite at scale 0 (the ideal track)."""
    wheel, _, ideal, irregular = setup
    position, rotation = wheelset_pose(ideal, 44.0, 1.0e-3, 0.45977)

    def outputs(scale):
        track = irregular.with_irregularity(
            Irregularity(irregular.irregularity.values, 0.0, STEP, scale))
        patches = search_wheelset(wheel, track, position, rotation)
        return jnp.stack([jnp.sum(patches.penetration), jnp.sum(patches.active * patches.y_wheel)])

    jacobian = jax.jit(jax.jacfwd(outputs))
    for scale in (0.0, 1.0):
        h = 1e-4
        central = (np.asarray(outputs(scale + h)) - np.asarray(outputs(scale - h))) / (2 * h)
        got = np.asarray(jacobian(scale))
        assert np.all(np.isfinite(got))
        np.testing.assert_allclose(got, central, rtol=1e-4, atol=1e-9)
