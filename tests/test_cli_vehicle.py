"""``jaxrail vehicle list`` and ``jaxrail vehicle show``: the built-in vehicles, and the
trailer's report (JSON keys and values, the figure) from the command line."""

import json

import numpy as np
import pytest

from jaxrail.cli import main
from jaxrail.vehicles import vehicle_names
from jaxrail.vehicles.trailer import GRAVITY

WEIGHT = 1e-6  # relative: the wheel loads at rest against the weight


def test_list_names_each_built_in_vehicle_with_its_description(capsys):
    assert main(["vehicle", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == vehicle_names()
    trailer = next(line for line in lines if line.startswith("trailer "))
    assert "11-body trailer" in trailer


def test_show_reports_the_trailers_masses_wheel_loads_and_modes(tmp_path, capsys):
    report, figure = tmp_path / "trailer.json", tmp_path / "trailer.png"
    assert main(["vehicle", "show", "trailer", "--json", str(report),
                 "--plot", str(figure)]) == 0
    text = capsys.readouterr().out
    assert "wheel loads at rest" in text and "lower sway" in text
    data = json.loads(report.read_text())
    assert {"total_mass_kg", "static_wheel_loads_N", "modes"} <= set(data)
    assert data["total_mass_kg"] == pytest.approx(32000 + 2 * 2615 + 4 * 1813, rel=1e-12)
    loads = data["static_wheel_loads_N"]
    assert len(loads) == 8  # 4 wheelsets, leading first, left then right
    weight = data["total_mass_kg"] * GRAVITY
    assert abs(sum(loads) / weight - 1.0) < WEIGHT
    np.testing.assert_allclose(loads, weight / 8, rtol=WEIGHT)
    for mode in data["modes"]:
        assert {"frequency_hz", "damping_ratio", "body", "motion"} <= set(mode)
    bounce = [m for m in data["modes"] if (m["body"], m["motion"]) == ("carbody", "bounce")]
    assert len(bounce) == 1 and 0.5 < bounce[0]["frequency_hz"] < 2.0
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_unknown_vehicle_is_named_with_the_built_in_ones(tmp_path, capsys):
    report = tmp_path / "report.json"
    assert main(["vehicle", "show", "no-such-vehicle", "--json", str(report)]) == 2
    error = capsys.readouterr().err
    assert ("jaxrail vehicle: error: no vehicle file 'no-such-vehicle': give a path or a "
            f"built-in name ({', '.join(vehicle_names())})") in error
    assert not report.exists()
