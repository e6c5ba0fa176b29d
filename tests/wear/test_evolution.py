"""The profile evolution's bookkeeping with a route whose wear is given (the runs replaced
by a fixed height loss per km, a hollow on the tread): the profile loses exactly the
smoothed loss times the distance, the file holds the completed steps only, an
interrupted evolution resumes from its last step without running it again, another
evolution in the same file is refused, and a hollow tread raises the equivalent
conicity (Polach 2011, Wear 271, 195-202; Sawley and Wu 2005, Wear 258, 1179-1186)."""

import json

import numpy as np
import pytest

from jaxrail.wear import evolution as evolution_module
from jaxrail.wear.evolution import RouteWear, evolve, smooth
from jaxrail.wear.route import load_route
from jaxrail.wear.summary import evolution_summary
from jaxrail.wear.wear_file import read_evolution

HOLLOW_PER_KM = 4e-7  # [m/km] peak height loss: 0.4 mm per 1000 km at the taping line
HOLLOW_WIDTH = 0.012  # [m] standard deviation


class Interrupted(Exception):
    pass


def _fake_route_wear(calls, fail_at=None):
    def route_wear(route, wheel, contact, built=None, cache_table=True):
        calls.append(wheel.name)
        if fail_at is not None and len(calls) == fail_at:
            raise Interrupted
        nodes = evolution_module.lateral_grid(built[1].wheel.surfaces[0].domain,
                                              evolution_module.GRID_SPACING)
        hollow = HOLLOW_PER_KM * np.exp(-0.5 * (nodes / HOLLOW_WIDTH) ** 2)
        depth = np.broadcast_to(hollow, (4, 2, len(nodes))).copy()
        rail_nodes = evolution_module.lateral_grid(built[2].rails.profile.domain,
                                                   evolution_module.GRID_SPACING)
        per_km = np.full((4, 2), 10.0)
        return RouteWear(volume_per_km=per_km, flange_fraction=np.zeros((4, 2)),
                         wheel_depth_per_km=depth, rail_depth_per_pass=np.zeros((2, len(rail_nodes))),
                         extrapolated_fraction=0.0, sections_volume_per_km=per_km[None],
                         sections_flange_per_km=np.zeros((1, 4, 2)),
                         sections_depth_per_km=depth[None], wheel_nodes=nodes,
                         rail_nodes=rail_nodes, completed=np.ones(1, bool), run_s=0.0,
                         compile_s=0.0)
    return route_wear


def test_interrupted_evolution_resumes_and_wears_the_given_loss(tmp_path, monkeypatch):
    route = load_route("straight-route")
    out = tmp_path / "wear.h5"
    calls = []
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls, fail_at=2))
    with pytest.raises(Interrupted):
        evolve(route, 2000.0, 1000.0, contact="online", out=out)
    first, attrs = read_evolution(out)
    assert attrs["completed_steps"] == 1 and list(first["distance_km"]) == [0.0, 1000.0]

    calls.clear()
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls))
    done = evolve(route, 2000.0, 1000.0, contact="online", out=out)
    assert len(calls) == 1  # only the second step ran
    evolution, attrs = read_evolution(out)
    assert attrs["completed_steps"] == 2 and list(evolution["distance_km"]) == [0.0, 1000.0,
                                                                                2000.0]
    nodes = evolution["profile_y"]
    hollow = HOLLOW_PER_KM * np.exp(-0.5 * (nodes / HOLLOW_WIDTH) ** 2)
    expected = evolution["profile_height"][0] - 2 * 1000.0 * smooth(nodes, hollow)
    np.testing.assert_allclose(evolution["profile_height"][-1], expected, rtol=0, atol=1e-12)
    # the smoothing keeps the volume: the loss integrates as the hollow does
    spacing = nodes[1] - nodes[0]
    assert np.sum(evolution["wear/height_loss"][1]) * spacing == pytest.approx(
        1000.0 * np.sum(hollow) * spacing, rel=1e-9)

    conicity = evolution["measures"]["equivalent_conicity"]
    assert conicity[2] > conicity[1] > conicity[0]  # the hollow raises the conicity
    summary = json.loads(json.dumps(evolution_summary(done, attrs)))
    assert len(summary["wear_volume_mm3_per_km"]) == 8
    assert summary["flange_wear_fraction"] == [0.0] * 8
    assert summary["equivalent_conicity"] == pytest.approx(list(conicity))
    assert summary["max_height_loss_per_step_mm"][0] == pytest.approx(
        1e3 * np.max(evolution["wear/height_loss"][0]))


def test_another_evolution_in_the_same_file_is_refused(tmp_path, monkeypatch):
    route = load_route("straight-route")
    out = tmp_path / "wear.h5"
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear([]))
    evolve(route, 1000.0, 1000.0, contact="online", out=out)
    with pytest.raises(ValueError, match="holds another evolution"):
        evolve(route, 3000.0, 1000.0, contact="online", out=out)


def test_max_depth_splits_a_step(tmp_path, monkeypatch):
    route = load_route("straight-route")
    calls = []
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls))
    # 0.4 mm per 1000 km at the peak (smoothed a little less): 0.15 mm sub-steps -> 3 runs
    evolution = evolve(route, 1000.0, 1000.0, contact="online", max_depth=0.15e-3)
    assert len(calls) == 3 and list(evolution["substeps"]) == [3]
    nodes = evolution["profile_y"]
    hollow = HOLLOW_PER_KM * np.exp(-0.5 * (nodes / HOLLOW_WIDTH) ** 2)
    np.testing.assert_allclose(evolution["wear/height_loss"][0], 1000.0 * smooth(nodes, hollow),
                               rtol=1e-12, atol=1e-15)


def test_an_evolution_stopped_inside_a_step_goes_on_from_its_last_sub_step(tmp_path,
                                                                          monkeypatch):
    """--max-depth splits the step into 3 runs; stopped in the third, the file keeps the
    first two, and the resumed evolution runs only the third and ends where an evolution
    that was never stopped ends."""
    route = load_route("straight-route")
    calls = []
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls))
    whole = evolve(route, 1000.0, 1000.0, contact="online", max_depth=0.15e-3)
    assert len(calls) == 3
    out = tmp_path / "wear.h5"
    calls.clear()
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls, fail_at=3))
    with pytest.raises(Interrupted):
        evolve(route, 1000.0, 1000.0, contact="online", out=out, max_depth=0.15e-3)
    saved, attrs = read_evolution(out)
    assert attrs["completed_steps"] == 0 and len(saved["pending"]["length_km"]) == 2
    calls.clear()
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear(calls))
    evolve(route, 1000.0, 1000.0, contact="online", out=out, max_depth=0.15e-3)
    assert len(calls) == 1  # only the third sub-step ran, on the profile the first two wore
    assert calls[0] == "worn"
    evolution, attrs = read_evolution(out)
    assert "pending" not in evolution and list(evolution["substeps"]) == [3]
    np.testing.assert_allclose(evolution["profile_height"][-1], whole["profile_height"][-1],
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(evolution["wear/volume_per_km"], whole["wear/volume_per_km"],
                               rtol=1e-15)


def test_the_figures_of_an_evolution_are_written(tmp_path, monkeypatch):
    """The three figures of `jaxrail wear --plots` from an evolution of two steps: PNG
    files, each whole (the figure module writes them atomically)."""
    from jaxrail.plots.wear import plot_measures, plot_wear_distribution, plot_worn_profiles

    route = load_route("straight-route")
    monkeypatch.setattr(evolution_module, "route_wear", _fake_route_wear([]))
    evolution = evolve(route, 2000.0, 1000.0, contact="online")
    for name, plot in (("profiles.png", plot_worn_profiles), ("measures.png", plot_measures),
                       ("distribution.png", plot_wear_distribution)):
        plot(evolution, tmp_path / name, title="test")
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
