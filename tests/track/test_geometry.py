"""Track geometry at arc length: against exact circles, Fresnel integrals, frames."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.special

from jaxrail import track as T
from jaxrail.profiles import uic60

R, LT, LA, LS = 300.0, 80.0, 200.0, 50.0  # radius, transition, arc, straight [m]
CANT = 0.150  # m
BASE = 1.5  # rail-centre distance [m]
OFFSET = 0.75303  # rail profile origin from track centre [m] (UIC60 1:40, 1435 mm)
RAILS = T.Rails(uic60("1:40"), OFFSET)
POS_TOL = 1e-9  # m, positions against closed forms
FRAME_TOL = 1e-13  # orthonormality
U, F, DX = 0.02, -0.004, 0.1  # a rail profile point (field-side lateral, height) and dx [m]


def make_curve(direction="left", radius=R, cant=CANT):
    return T.Track.from_segments(T.curve_layout(radius, direction, cant, LS, LT, LA, LS),
                                 rails=RAILS)


LEFT = make_curve("left")
RIGHT = make_curve("right")
JOINTS = np.array([LS, LS + LT, LS + LT + LA, LS + 2 * LT + LA])
TOTAL = 2 * LS + 2 * LT + LA


def _evaluate(track, s):
    """Every geometry function at scalar s (one compiled function for the module)."""
    origin, a = T.rail_frame(track, s, -1)
    return dict(
        pos=T.centreline_position(track, s),
        heading=T.heading(track, s),
        curvature=T.curvature(track, s),
        superelevation=T.superelevation(track, s),
        cant=T.cant_angle(track, s),
        frame=T.track_frame(track, s),
        rail_right=origin,
        rail_frame=a,
        point_left=T.rail_point(track, s, 1, U, F, DX),
        rail_left=T.rail_frame(track, s, "left")[0],
        point_right=T.rail_point(track, s, "right", U, F, DX),
    )


FLAT_KEYS = ("pos", "heading", "curvature", "superelevation", "cant", "frame")
FLAT_KEYS += ("rail_right", "rail_frame", "point_left")


def flatten(values, axis=-1):
    """The FLAT_KEYS entries of an _evaluate result as one vector (per point)."""
    n = np.shape(values["heading"])
    return np.concatenate([np.reshape(values[k], n + (-1,)) for k in FLAT_KEYS], axis=axis)


def _flat(track, s):
    """Every public geometry function at s, as one vector of 31 numbers (for grads)."""
    origin, a = T.rail_frame(track, s, -1)
    parts = (
        T.centreline_position(track, s),
        T.heading(track, s),
        T.curvature(track, s),
        T.superelevation(track, s),
        T.cant_angle(track, s),
        T.track_frame(track, s),
        origin,
        a,
        T.rail_point(track, s, 1, U, F, DX),
    )
    return jnp.concatenate([jnp.ravel(x) for x in parts])


WEIGHTS = np.linspace(0.5, 2.0, 31)  # a fixed projection for the reverse-mode check
_evaluate_v = jax.jit(jax.vmap(_evaluate, (None, 0)))
_d_forward_v = jax.jit(jax.vmap(jax.jacfwd(_flat, 1), (None, 0)))
_d_reverse_v = jax.jit(jax.vmap(jax.grad(lambda tr, s: _flat(tr, s) @ WEIGHTS, 1), (None, 0)))
flat_scalar = jax.jit(_flat)


def _padded(fn, size):
    """Call a vmapped kernel on a fixed-size batch, so that it compiles once per track
    structure whatever the number of points a test asks for."""

    def call(track, s):
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        assert s.size <= size
        out = fn(track, np.concatenate([s, np.zeros(size - s.size)]))
        return jax.tree.map(lambda x: np.asarray(x[: s.size]), out)

    return call


evaluate = _padded(_evaluate_v, 1024)
d_forward = _padded(_d_forward_v, 8)
d_reverse = _padded(_d_reverse_v, 8)


def pos_v(track, s):
    return evaluate(track, s)["pos"]


def head_v(track, s):
    return evaluate(track, s)["heading"]


def curv_v(track, s):
    return evaluate(track, s)["curvature"]


def sup_v(track, s):
    return evaluate(track, s)["superelevation"]


def cant_v(track, s):
    return evaluate(track, s)["cant"]


def frame_v(track, s):
    return evaluate(track, s)["frame"]


def at(track, s):
    """All values at one arc length (through the vmapped function)."""
    return jax.tree.map(lambda x: x[0], evaluate(track, s))


def central_difference(f, x, h):
    return (f(x + h) - f(x - h)) / (2.0 * h)


# ---------------------------------------------------------------- closed forms


@pytest.mark.parametrize("direction", ["left", "right"])
def test_arc_matches_exact_circle(direction):
    # A lone arc from (X0, Y0) with heading h0, nearly a full turn.
    x0, y0, h0, radius = 12.0, -7.0, 0.4, 180.0
    length = 0.95 * 2 * np.pi * radius
    track = T.Track.from_segments(
        [T.Arc(length, radius, direction)], start=(x0, y0, h0)
    )
    sign = 1.0 if direction == "left" else -1.0
    s = np.linspace(0.0, length, 101)
    centre = np.array([x0 - sign * radius * np.sin(h0), y0 + sign * radius * np.cos(h0)])
    angle = h0 + sign * s / radius
    exact = np.stack(
        [centre[0] + sign * radius * np.sin(angle), centre[1] - sign * radius * np.cos(angle)], 1
    )
    got = np.asarray(pos_v(track, s))
    np.testing.assert_allclose(got[:, :2], exact, rtol=0, atol=POS_TOL)
    np.testing.assert_array_equal(got[:, 2], 0.0)
    np.testing.assert_allclose(head_v(track, s), angle, rtol=0, atol=1e-13)
    np.testing.assert_allclose(curv_v(track, s), sign / radius, rtol=1e-15)


def test_integral_from_the_nearest_sample_with_the_fewest_samples():
    # A nearly full turn of 120 m radius with 8 samples (the fewest a layout takes):
    # half a spacing turns the heading by 0.37 rad. The circle at points on both sides
    # of each switch to the next sample (the spacings' midpoints), and no jump there.
    x0, y0, h0, radius = 3.0, 5.0, -0.2, 120.0
    length = 0.95 * 2 * np.pi * radius
    fewest = T.Track.from_segments([T.Arc(length, radius, "left")], start=(x0, y0, h0),
                                   samples_per_segment=8)
    spacing = length / 8
    switches = spacing * (np.arange(8) + 0.5)
    s = np.concatenate([switches - 1e-7, switches + 1e-7, np.linspace(0.0, length, 501)])
    centre = np.array([x0 - radius * np.sin(h0), y0 + radius * np.cos(h0)])
    angle = h0 + s / radius
    exact = np.stack([centre[0] + radius * np.sin(angle), centre[1] - radius * np.cos(angle)], 1)
    got = np.asarray(pos_v(fewest, s))[:, :2]
    np.testing.assert_allclose(got, exact, rtol=0, atol=1e-11)
    # across each switch the point moves by 2e-7 m along the tangent, to 1e-12 m
    step = got[8:16] - got[:8]
    tangent = np.stack([np.cos(h0 + switches / radius), np.sin(h0 + switches / radius)], 1)
    np.testing.assert_allclose(step, 2e-7 * tangent, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="samples_per_segment must be an int >= 8"):
        T.Track.from_segments([T.Arc(length, radius, "left")], samples_per_segment=7)


def test_small_angle_series_against_the_library_cos_and_sin():
    # |angle| <= 0.8 rad: within an ulp of numpy's cos and sin; jit, vmap and the
    # derivative (-sin, cos) by forward and reverse mode
    from jaxrail.track.geometry import small_angle_cos_sin
    angle = np.linspace(-0.8, 0.8, 2001)
    cos, sin = jax.jit(jax.vmap(small_angle_cos_sin))(jnp.asarray(angle))
    np.testing.assert_allclose(cos, np.cos(angle), rtol=0, atol=3e-16)
    np.testing.assert_allclose(sin, np.sin(angle), rtol=0, atol=3e-16)
    for a in (0.0, 0.3, -0.75):
        d_cos, d_sin = jax.jacfwd(small_angle_cos_sin)(jnp.float64(a))
        np.testing.assert_allclose([d_cos, d_sin], [-np.sin(a), np.cos(a)], atol=1e-15)
        assert float(jax.grad(lambda x: small_angle_cos_sin(x)[1])(jnp.float64(a))) == \
            pytest.approx(np.cos(a), abs=1e-15)


def test_frame_and_heading_without_angles_match_the_angles():
    # the frame from the sample's tangent and sin(cant) = e / base against the one
    # built from heading(s) and cant_angle(s) with the library's cos and sin
    s = np.linspace(-20.0, TOTAL + 20.0, 397)
    for track in (LEFT, RIGHT):
        h = np.asarray(jax.vmap(lambda x: T.heading(track, x))(s))
        phi = np.asarray(jax.vmap(lambda x: T.cant_angle(track, x))(s))
        ch, sh, cp, sp = np.cos(h), np.sin(h), np.cos(phi), np.sin(phi)
        expected = np.stack([np.stack([ch, sh, 0 * ch], 1),
                             np.stack([-sh * cp, ch * cp, -sp], 1),
                             np.stack([-sh * sp, ch * sp, cp], 1)], 2)
        frames = np.asarray(jax.jit(jax.vmap(lambda x: T.track_frame(track, x)))(s))
        np.testing.assert_allclose(frames, expected, rtol=0, atol=2e-15)


def clothoid_reference(sigma, radius, length):
    """Clothoid from the origin, heading 0, curvature sigma / (radius * length)."""
    a = np.sqrt(radius * length * np.pi)
    fs, fc = scipy.special.fresnel(sigma / a)
    return a * fc, a * fs


def test_curve_matches_fresnel_and_circle():
    # Straight (x axis), clothoid (Fresnel integrals), then the arc (a circle).
    s_tr = np.linspace(0.0, LT, 41)
    got = np.asarray(pos_v(LEFT, LS + s_tr))
    xr, yr = clothoid_reference(s_tr, R, LT)
    np.testing.assert_allclose(got[:, 0], LS + xr, rtol=0, atol=POS_TOL)
    np.testing.assert_allclose(got[:, 1], yr, rtol=0, atol=POS_TOL)
    np.testing.assert_allclose(head_v(LEFT, LS + s_tr), s_tr**2 / (2 * R * LT), atol=1e-14)
    # Arc: circle tangent to the clothoid end.
    xe, ye = clothoid_reference(np.array(LT), R, LT)
    he = LT / (2 * R)
    centre = np.array([LS + xe - R * np.sin(he), ye + R * np.cos(he)])
    s_arc = np.linspace(0.0, LA, 41)
    ang = he + s_arc / R
    got = np.asarray(pos_v(LEFT, LS + LT + s_arc))
    np.testing.assert_allclose(got[:, 0], centre[0] + R * np.sin(ang), rtol=0, atol=POS_TOL)
    np.testing.assert_allclose(got[:, 1], centre[1] - R * np.cos(ang), rtol=0, atol=POS_TOL)


def test_right_curve_mirrors_left():
    s = np.linspace(-20.0, TOTAL + 20.0, 77)
    pl, pr = np.asarray(pos_v(LEFT, s)), np.asarray(pos_v(RIGHT, s))
    np.testing.assert_allclose(pr[:, 0], pl[:, 0], atol=1e-12)
    np.testing.assert_allclose(pr[:, 1], -pl[:, 1], atol=1e-12)
    np.testing.assert_allclose(sup_v(RIGHT, s), -np.asarray(sup_v(LEFT, s)), atol=1e-15)



def test_left_turns_left_right_turns_right():
    turn = LA / R + LT / R  # arc plus two half transitions [rad]
    assert float(at(LEFT, TOTAL)["heading"]) == pytest.approx(turn, abs=1e-13)
    assert float(at(RIGHT, TOTAL)["heading"]) == pytest.approx(-turn, abs=1e-13)
    s = np.linspace(LS + 1.0, TOTAL, 50)
    assert np.all(np.asarray(pos_v(LEFT, s))[:, 1] > 0)
    assert np.all(np.asarray(pos_v(RIGHT, s))[:, 1] < 0)
    s = np.linspace(LS, LS + 2 * LT + LA, 50)  # heading grows through the curve
    assert np.all(np.diff(np.asarray(head_v(LEFT, s))) > 0)
    assert np.all(np.diff(np.asarray(head_v(RIGHT, s))) < 0)


def test_curvature_and_cant_linear_on_transitions():
    sigma = np.array([0.0, 7.5, 20.0, 40.0, 61.0, 79.9])
    e_in, k_in = sup_v(LEFT, LS + sigma), curv_v(LEFT, LS + sigma)
    np.testing.assert_allclose(k_in, sigma / (R * LT), rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(e_in, CANT * sigma / LT, rtol=1e-13, atol=1e-16)
    start_out = LS + LT + LA
    e_out, k_out = sup_v(LEFT, start_out + sigma), curv_v(LEFT, start_out + sigma)
    np.testing.assert_allclose(k_out, (1 - sigma / LT) / R, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(e_out, CANT * (1 - sigma / LT), rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(
        cant_v(LEFT, LS + sigma), np.arcsin(CANT * sigma / LT / BASE), rtol=1e-13, atol=1e-16
    )
    # Arc: constant, signed.
    s_arc = LS + LT + np.array([0.0, 100.0, 199.0])
    np.testing.assert_allclose(curv_v(RIGHT, s_arc), -1.0 / R, rtol=1e-15)
    np.testing.assert_allclose(sup_v(RIGHT, s_arc), -CANT, rtol=1e-15)
    np.testing.assert_allclose(cant_v(RIGHT, s_arc), -np.arcsin(CANT / BASE), rtol=1e-15)


def test_extension_beyond_ends_is_straight():
    s = np.array([-30.0, -1.0, TOTAL + 1.0, TOTAL + 50.0, TOTAL])
    v = evaluate(LEFT, s)
    p = np.asarray(v["pos"])
    np.testing.assert_allclose(p[:2, 0], s[:2], atol=1e-12)
    np.testing.assert_allclose(p[:2, 1], 0.0, atol=1e-12)
    end, h = p[4], float(v["heading"][4])
    for k in (2, 3):
        d = s[k] - TOTAL
        straight_on = end[:2] + d * np.array([np.cos(h), np.sin(h)])
        np.testing.assert_allclose(p[k, :2], straight_on, atol=1e-11)
    np.testing.assert_allclose(v["heading"][:4], [0.0, 0.0, h, h], atol=1e-15)
    np.testing.assert_allclose(v["curvature"], 0.0, atol=0)
    np.testing.assert_allclose(v["superelevation"], 0.0, atol=0)


# ---------------------------------------------------------------- frames and joints


def test_frames_orthonormal_right_handed():
    s = np.concatenate(
        [
            np.linspace(-5.0, TOTAL + 5.0, 1001),
            JOINTS,
            np.nextafter(JOINTS, -np.inf),
            np.nextafter(JOINTS, np.inf),
        ]
    )
    for track in (LEFT, RIGHT):
        f = np.asarray(frame_v(track, s))
        gram = np.einsum("kij,kil->kjl", f, f)
        assert np.max(np.abs(gram - np.eye(3))) < FRAME_TOL
        cross = np.cross(f[:, :, 0], f[:, :, 1])
        assert np.max(np.abs(cross - f[:, :, 2])) < FRAME_TOL
        np.testing.assert_allclose(np.linalg.det(f), 1.0, atol=FRAME_TOL)
        np.testing.assert_array_equal(f[:, 2, 0], 0.0)  # t horizontal (planar track)
    # On the canted arc of a left curve n dips (right rail up) and b leans left.
    f = at(LEFT, LS + LT + 10.0)["frame"]
    phi = np.arcsin(CANT / BASE)
    assert f[2, 1] == pytest.approx(-np.sin(phi), abs=1e-15)
    assert f[2, 2] == pytest.approx(np.cos(phi), abs=1e-15)
    assert f[:2, 2] @ f[:2, 1] > 0.0


def test_position_c1_at_joints():
    # Each joint evaluated from both segments (the value just below the joint
    # belongs to the previous segment).
    below = np.nextafter(JOINTS, -np.inf)
    for track in (LEFT, RIGHT):
        va, vb = evaluate(track, JOINTS), evaluate(track, below)
        gap = np.linalg.norm(np.asarray(va["pos"]) - np.asarray(vb["pos"]), axis=1)
        assert np.max(gap) < 1e-9  # m
        # heading: tangent continuous (C1); no curvature or cant steps in this layout
        for key in ("heading", "curvature", "superelevation"):
            assert np.max(np.abs(np.asarray(va[key]) - np.asarray(vb[key]))) < 1e-12, key


# ---------------------------------------------------------------- rails


def test_cant_raises_outer_rail():
    z_expected = OFFSET * CANT / BASE  # OFFSET * sin(phi)
    for track, sign in ((LEFT, 1.0), (RIGHT, -1.0)):
        v = at(track, LS + LT + 50.0)
        if sign > 0:
            outer, inner = v["rail_right"], v["rail_left"]
        else:
            outer, inner = v["rail_left"], v["rail_right"]
        assert outer[2] > 0.0 > inner[2]
        assert outer[2] == pytest.approx(z_expected, abs=1e-14)
        assert inner[2] == pytest.approx(-z_expected, abs=1e-14)
        np.testing.assert_allclose(0.5 * (outer + inner), v["pos"], atol=1e-12)
        assert np.linalg.norm(outer - inner) == pytest.approx(2 * OFFSET, abs=1e-12)


def test_rail_point_mirrors_field_side():
    s = 30.0  # on the entry straight: origin, heading 0, no cant
    v = at(LEFT, s)
    # Field side is +Y on the left rail, -Y on the right: mirror images.
    np.testing.assert_allclose(v["point_left"], [s + DX, OFFSET + U, F], atol=1e-14)
    np.testing.assert_allclose(v["point_right"], [s + DX, -(OFFSET + U), F], atol=1e-14)
    np.testing.assert_allclose(v["rail_left"], [s, OFFSET, 0.0], atol=1e-14)
    # On a canted curve: origin + A (dx, side u, f).
    v = at(LEFT, 200.0)
    a = v["frame"]
    np.testing.assert_allclose(v["point_right"], v["rail_right"] + a @ [DX, -U, F], atol=1e-13)
    np.testing.assert_allclose(v["rail_frame"], a, atol=0)


def test_bad_side_and_shapes():
    with pytest.raises(ValueError, match="side must be"):
        T.rail_frame(LEFT, 1.0, "up")
    with pytest.raises(ValueError, match="side must be"):
        T.rail_point(LEFT, 1.0, 2, 0.0, 0.0)
    with pytest.raises(ValueError, match="s must be a scalar"):
        T.centreline_position(LEFT, jnp.zeros(3))


# ---------------------------------------------------------------- jit, vmap, grad


def test_vmap_matches_scalar_jit():
    s = np.array([12.0, LS + 40.0, LS + LT + 173.25])
    batch = flatten(evaluate(LEFT, s))
    for k, sk in enumerate(s):
        np.testing.assert_allclose(batch[k], flat_scalar(LEFT, sk), rtol=0, atol=1e-13)
    # side as a traced +-1 (vmapped over both rails) agrees with the strings
    sides = jax.jit(jax.vmap(lambda sd: T.rail_point(LEFT, s[2], sd, U, F, DX)))
    both = sides(jnp.array([1.0, -1.0]))
    v = at(LEFT, s[2])
    np.testing.assert_allclose(both[0], v["point_left"], atol=1e-13)
    np.testing.assert_allclose(both[1], v["point_right"], atol=1e-13)


def test_grad_in_s_against_geometry_and_finite_differences():
    s = np.array([20.0, LS + 33.0, LS + LT + 90.0, LS + LT + LA + 5.0, TOTAL - 1.0])
    fwd, rev = d_forward(LEFT, s), d_reverse(LEFT, s)
    v = evaluate(LEFT, s)
    np.testing.assert_allclose(fwd[:, 0:3], v["frame"][:, :, 0], atol=1e-12)  # dc/ds = t
    np.testing.assert_allclose(fwd[:, 3], v["curvature"], atol=1e-15)  # dh/ds = kappa
    rate_e, rate_k = CANT / LT, 1 / (R * LT)
    np.testing.assert_allclose(fwd[:, 4], [0, rate_k, 0, -rate_k, 0], atol=1e-16)
    np.testing.assert_allclose(fwd[:, 5], [0, rate_e, 0, -rate_e, 0], atol=1e-15)
    h = 1e-4
    fd = (flatten(evaluate(LEFT, s + h)) - flatten(evaluate(LEFT, s - h))) / (2 * h)
    np.testing.assert_allclose(fwd, fd, rtol=0, atol=1e-9)
    np.testing.assert_allclose(rev, fwd @ WEIGHTS, rtol=0, atol=1e-13)
    assert abs(float(fwd[1, 6])) > 1e-4  # the transition really ramps the cant angle


def test_grad_rail_point_in_profile_coordinates():
    s = LS + LT + 40.0

    def point(q):
        track = RIGHT.with_rails(T.Rails(RIGHT.rails.profile, q[0]))
        return T.rail_point(track, s, "right", q[1], q[2], q[3])

    jac = jax.jit(jax.jacrev(point))(jnp.array([OFFSET, 0.01, 0.002, 0.0]))
    f = at(RIGHT, s)["frame"]
    np.testing.assert_allclose(jac[:, 0], -f[:, 1], atol=1e-15)  # lateral offset
    np.testing.assert_allclose(jac[:, 1], -f[:, 1], atol=1e-15)  # u mirrored
    np.testing.assert_allclose(jac[:, 2], f[:, 2], atol=1e-15)  # f along b
    np.testing.assert_allclose(jac[:, 3], f[:, 0], atol=1e-15)  # dx along t


def _rail_and_end(params):
    radius, cant = params
    track = make_curve("left", radius, cant)
    origin, _ = T.rail_frame(track, LS + LT + LA - 10.0, "right")
    end = T.centreline_position(track, TOTAL + 10.0)
    return jnp.concatenate([origin, end, T.cant_angle(track, LS + 10.0)[None]])


def test_grad_wrt_radius_and_cant_through_built_track():
    # Central differences and a batched (vmapped) build from one compiled function.
    hr, hc = 1e-3, 1e-6
    x = np.array([[R, CANT], [R + hr, CANT], [R - hr, CANT], [R, CANT + hc], [R, CANT - hc]])
    vals = np.asarray(jax.jit(jax.vmap(_rail_and_end))(x))
    fd = np.stack([(vals[1] - vals[2]) / (2 * hr), (vals[3] - vals[4]) / (2 * hc)], axis=1)
    assert abs(fd[0, 0]) > 1e-3 and abs(fd[2, 1]) > 0.1  # radius and cant really act
    assert abs(fd[6, 1]) > 0.01
    # Reverse mode through the track build, on a weighted sum of all outputs.
    w = np.array([1.0, -2.0, 3.0, 0.5, 1.5, 0.0, 2.0])
    grad = jax.jit(jax.grad(lambda p: _rail_and_end(p) @ w))(jnp.array([R, CANT]))
    np.testing.assert_allclose(grad, w @ fd, rtol=1e-6)
