"""Track irregularities: spectra against their quadrature, the interpolation, the rails'
displacement convention, defects, measured files and their bad input."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate, signal

from jaxrail.cli import main
from jaxrail.track import CHANNELS, Irregularity, Rails, rail_frame, standard_rails, straight_track
from jaxrail.track.defects import cosine_defect
from jaxrail.track.measured import parse_irregularity, read_irregularity, write_irregularity
from jaxrail.track.spectra import SPECTRA, band_variance, check_band, realisation

SEEDS = 100
BANDS = ((3.0, 25.0), (25.0, 70.0))


def _welch_band_variances(values, step):
    """Variance (bands, channels) of ``values`` (N, 4) [m] in :data:`BANDS` from SciPy's
    Welch PSD (an estimator independent of the generator)."""
    freq, psd = signal.welch(values.T, fs=2 * math.pi / step, nperseg=4096, axis=-1)
    out = []
    for lo, hi in BANDS:
        inside = (freq >= 2 * math.pi / hi) & (freq <= 2 * math.pi / lo)
        out.append(np.sum(psd[:, inside], axis=-1) * (freq[1] - freq[0]))
    return np.array(out)


@pytest.mark.parametrize("name", ["german-low", "german-high", "fra-4"])
def test_band_standard_deviations_match_the_spectrum_within_3_percent(name):
    spectrum = SPECTRA[name]
    draw = jax.jit(lambda seed: realisation(name, 2000.0, 0.25, seed).values)
    estimates = np.mean([_welch_band_variances(np.asarray(draw(seed)), 0.25)
                         for seed in range(SEEDS)], axis=0)
    channels = range(4) if name.startswith("german") else (0, 1)
    for b, (lo, hi) in enumerate(BANDS):
        for c in channels:
            # the reference: the spectrum integrated by adaptive quadrature (SciPy)
            psd = lambda w: float(spectrum.psd(jnp.asarray(w))[c])  # noqa: E731
            reference, _ = integrate.quad(psd, 2 * math.pi / hi, 2 * math.pi / lo, limit=200)
            assert math.sqrt(estimates[b, c]) == pytest.approx(math.sqrt(reference), rel=0.03), (
                name, (lo, hi), CHANNELS[c])
            assert band_variance(spectrum, (lo, hi))[c] == pytest.approx(reference, rel=1e-8)
    if not name.startswith("german"):  # FRA: vertical and alignment only
        assert np.all(estimates[:, 2:] == 0.0)


def test_german_constants_and_levels():
    low, high = SPECTRA["german-low"], SPECTRA["german-high"]
    # ORE B176 as two public codes give it (docs/track.md): the high level is the rougher
    assert (low.a_v, low.a_a, low.a_g) == (4.032e-7, 2.119e-7, 5.32e-8)
    assert (high.a_v, high.a_a, high.a_g) == (1.080e-6, 6.125e-7, 1.032e-7)
    w = jnp.linspace(0.05, 2.0, 20)
    assert np.all(np.asarray(high.psd(w)) > np.asarray(low.psd(w)))
    # cross level: the angle spectrum times (1.5 m)^2
    angle = low.a_v / 0.75 ** 2 * low.wc ** 2 * w ** 2 / (
        (w ** 2 + low.wr ** 2) * (w ** 2 + low.wc ** 2) * (w ** 2 + low.ws ** 2))
    np.testing.assert_allclose(low.psd(w)[2], 1.5 ** 2 * angle, rtol=1e-12)


def test_a_seed_gives_the_same_realisation_and_another_seed_a_different_one():
    a = realisation("german-low", 300.0, 0.25, 7).values
    b = realisation("german-low", 300.0, 0.25, 7).values
    c = realisation("german-low", 300.0, 0.25, 8).values
    np.testing.assert_array_equal(a, b)
    assert np.max(np.abs(np.asarray(a) - np.asarray(c))) > 1e-3


def test_realisations_batch_under_vmap_and_scale_linearly():
    seeds = jnp.arange(3)
    batch = jax.vmap(lambda s: realisation("german-high", 200.0, 0.25, s).values)(seeds)
    for k in range(3):
        np.testing.assert_array_equal(batch[k], realisation("german-high", 200.0, 0.25, k).values)
    half = realisation("german-high", 200.0, 0.25, 1, scale=0.5)
    np.testing.assert_allclose(jax.vmap(half.at)(jnp.linspace(0, 200, 9)),
                               0.5 * jax.vmap(realisation("german-high", 200.0, 0.25, 1).at)(
                                   jnp.linspace(0, 200, 9)), rtol=1e-14)


def test_interpolation_is_exact_for_quadratics_and_differentiable():
    step, start = 0.25, -3.0
    s = start + step * np.arange(40)
    quadratic = lambda x: np.stack([1e-3 * x ** 2, -2e-3 * x, 0.5e-3 + 0 * x,  # noqa: E731
                                    1e-4 * x ** 2 - 1e-3 * x], axis=-1)
    irregularity = Irregularity(quadratic(s), start, step)
    x = np.linspace(-2.7, 5.3, 37)
    at = jax.jit(jax.vmap(irregularity.at))
    np.testing.assert_allclose(at(x), quadratic(x), atol=1e-15)
    # jit, vmap and grad in s: the slope of the quadratic, against central differences
    slope = jax.vmap(jax.jacfwd(irregularity.at))(jnp.asarray(x))
    h = 1e-6
    central = (at(x + h) - at(x - h)) / (2 * h)
    np.testing.assert_allclose(slope, central, rtol=1e-6, atol=1e-12)
    # and in the scale
    d_scale = jax.grad(lambda k: Irregularity(quadratic(s), start, step, k).at(1.1)[0])(2.0)
    assert float(d_scale) == pytest.approx(1e-3 * 1.1 ** 2, rel=1e-12)


def test_beyond_the_samples_each_channel_keeps_its_end_value():
    irregularity = realisation("german-low", 50.0, 0.25, 3)
    values = np.asarray(irregularity.values)
    np.testing.assert_allclose(irregularity.at(-10.0), values[0], atol=1e-16)
    np.testing.assert_allclose(irregularity.at(80.0), values[-1], atol=1e-16)


def test_rails_move_by_the_documented_convention():
    a, v, c, g = 2e-3, -1e-3, 0.6e-3, 0.8e-3
    irregularity = Irregularity(np.tile([a, v, c, g], (4, 1)), 0.0, 10.0)
    ideal = straight_track(40.0, rails=Rails(standard_rails().profile, 0.75))
    irregular = ideal.with_irregularity(irregularity)
    for side, y, z in ((1.0, a + g / 2, v + c / 2), (-1.0, a - g / 2, v - c / 2)):
        moved = np.asarray(rail_frame(irregular, 12.0, side)[0])
        design = np.asarray(rail_frame(ideal, 12.0, side)[0])
        np.testing.assert_allclose(moved - design, [0.0, y, z], atol=1e-15)
    # the left rail lies higher than the right by the cross level, the gauge is wider
    left, right = (np.asarray(rail_frame(irregular, 12.0, k)[0]) for k in (1.0, -1.0))
    assert left[2] - right[2] == pytest.approx(c, abs=1e-15)
    assert left[1] - right[1] == pytest.approx(1.5 + g, abs=1e-15)


def test_cosine_defect_has_its_shape_and_is_zero_outside():
    defect = cosine_defect("vertical", wavelength=10.0, amplitude=0.005, position=60.0)
    s = np.linspace(50.0, 80.0, 3001)
    got = np.asarray(jax.vmap(defect.at)(s))
    exact = np.where((s >= 60) & (s <= 70), -0.0025 * (1 - np.cos(2 * np.pi * (s - 60) / 10)), 0)
    assert np.abs(got[:, 1] - exact).max() < 5e-4 * 0.005
    assert got[:, 1].min() == pytest.approx(-0.005, rel=1e-9)
    assert np.all(got[:, [0, 2, 3]] == 0.0)
    lateral = cosine_defect("lateral", 4.0, 0.002, 10.0)
    assert float(lateral.at(12.0)[0]) == pytest.approx(-0.002, rel=1e-9)


@pytest.mark.parametrize("call, message", [
    (lambda: cosine_defect("twist", 10.0, 0.001, 0.0), "unknown defect kind 'twist'"),
    (lambda: cosine_defect("lateral", -1.0, 0.001, 0.0), "wavelength must be > 0"),
    (lambda: realisation("german-medium", 100.0), "unknown irregularity spectrum"),
    (lambda: realisation("fra-7", 100.0), "fra-1, fra-2"),
    (lambda: realisation("german-low", 100.0, band=(150.0, 3.0)), "ends swapped"),
    (lambda: realisation("german-low", 100.0, scale=-1.0), "scale must be >= 0"),
    (lambda: realisation("german-low", 100.0, step=2.0), "cannot carry"),
    (lambda: check_band("3-150"), "two wavelengths"),
])
def test_bad_arguments_are_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --- measured files ------------------------------------------------------------------

HEADER = "distance [m],alignment [mm],vertical level [mm],cross level [mm],gauge deviation [mm]"


def test_written_file_reads_back_to_the_same_samples(tmp_path):
    irregularity = realisation("german-high", 120.0, 0.25, 11, scale=1.3)
    path = tmp_path / "line.csv"
    write_irregularity(path, irregularity, "a comment")
    back = read_irregularity(path)
    np.testing.assert_allclose(np.asarray(back.values),
                               1.3 * np.asarray(irregularity.values), rtol=1e-14, atol=1e-18)
    assert float(back.step) == pytest.approx(0.25, rel=1e-14)
    assert float(back.start) == 0.0
    text = path.read_text()
    assert text.startswith("# a comment\n" + HEADER + "\n")


def test_columns_may_come_in_any_order():
    text = ("vertical level [mm],distance [m],gauge deviation [mm],alignment [mm],"
            "cross level [mm]\n" + "".join(f"{k},{0.5 * k},0.3,1.0,-2.0\n" for k in range(6)))
    irregularity = parse_irregularity(text)
    np.testing.assert_allclose(irregularity.values[2], [1e-3, 2e-3, -2e-3, 0.3e-3])
    assert float(irregularity.step) == 0.5


def _rows(n=6, step=0.25, value="1.0"):
    return "".join(f"{k * step},{value},0.5,0.2,0.1\n" for k in range(n))


@pytest.mark.parametrize("text, message", [
    (HEADER + "\n0.0,1,1,1,1\n0.25,1,1,1,1\n0.6,1,1,1,1\n0.75,1,1,1,1\n", "unequal spacing"),
    ("distance [m],alignment [mm],vertical level [mm],gauge deviation [mm]\n" + _rows(),
     "missing column.*cross level"),
    (HEADER + "\n" + _rows().replace("0.5,0.2", "abc,0.2", 1), "'abc' is not a number"),
    (HEADER + "\n" + "".join(f"{k * 0.25},0.001,0.002,0.0005,0.0001\n" for k in range(6)),
     "look like metres"),
    (HEADER + "\n" + _rows(value="2500"), "not a track irregularity"),
    (HEADER + "\n" + _rows(n=3), "at least 4"),
    ("", "empty irregularity file"),
    (HEADER + ",twist [mm]\n" + _rows(), "unknown column"),
    (HEADER + "\n0.0,1,1,1\n" + _rows(), "4 cells"),
])
def test_bad_measured_files_are_named(text, message):
    with pytest.raises(ValueError, match=message):
        parse_irregularity(text, "line.csv")


def test_binary_file_is_refused(tmp_path):
    path = tmp_path / "line.csv"
    path.write_bytes(bytes(range(256)))
    with pytest.raises(ValueError, match="not a text"):
        read_irregularity(path)


# --- command line --------------------------------------------------------------------

def test_command_writes_a_realisation_with_its_header_and_figure(tmp_path, capsys):
    csv, png = tmp_path / "out.csv", tmp_path / "psd.png"
    assert main(["track", "irregularities", "--spectrum", "german-low", "--length", "200",
                 "--step", "0.25", "--seed", "7", "--csv", str(csv), "--plot", str(png)]) == 0
    lines = csv.read_text().splitlines()
    assert lines[0].startswith("# jaxrail track irregularities: german-low, seed 7")
    assert lines[1] == HEADER
    assert len(lines) == 2 + 801
    np.testing.assert_allclose(np.asarray(read_irregularity(csv).values),
                               np.asarray(realisation("german-low", 200.0, 0.25, 7).values),
                               rtol=1e-14, atol=1e-18)
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize("args, message", [
    (["--spectrum", "german", "--length", "100"], "unknown irregularity spectrum 'german'"),
    (["--spectrum", "fra-9", "--length", "100"], "unknown irregularity spectrum 'fra-9'"),
    (["--spectrum", "german-low", "--length", "100", "--band", "150:3"], "ends swapped"),
    (["--spectrum", "german-low", "--length", "100", "--band", "3-150"], "--band must be LO:HI"),
    (["--spectrum", "german-low", "--length", "100", "--scale", "-1"], "--scale must be >= 0"),
    (["--spectrum", "german-low", "--length", "-5"], "--length must be"),
])
def test_command_bad_input_is_named(args, message, capsys):
    assert main(["track", "irregularities", *args]) == 2
    assert message in capsys.readouterr().err
