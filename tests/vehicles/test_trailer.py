"""The 11-body trailer: parameter file, topology, static equilibrium on straight track,
and a short run with the paper's 2 mm misalignment.

The static loads are computed here by hand from the Manchester benchmark masses of
shared/reference/vehicle.md, not from jaxrail."""

import jax
import numpy as np
import pytest

from jaxrail.multibody.forces import element_deformation
from jaxrail.simulate import DerailmentLimits, SolverOptions, simulate
from jaxrail.track import straight_track
from jaxrail.vehicles import read_vehicle_data, trailer, trailer_values

G = 9.81
CARBODY, BOGIE, UNSPRUNG = 32000.0, 2615.0, 1813.0  # [kg], reference [V-src]
WEIGHT = (CARBODY + 2 * BOGIE + 4 * UNSPRUNG) * G
PRIMARY_KZ, SECONDARY_KZ = 1.22e6, 430e3  # [N/m] per element [V-src]


def test_every_value_has_a_source_and_tag():
    entries = read_vehicle_data()
    assert len(entries) == len(trailer_values())  # nothing dropped
    for key, entry in entries.items():
        assert entry["source"].strip() and entry["unit"].strip(), key
    checked = {k: e["value"] for k, e in entries.items() if e["tag"] == "V-src"}
    assert checked["carbody.mass"] == CARBODY and checked["bogie.mass"] == BOGIE
    assert checked["primary.vertical_stiffness"] == PRIMARY_KZ
    assert checked["secondary.vertical_stiffness"] == SECONDARY_KZ
    values = trailer_values()
    assert values["wheelset.mass"] + values["axlebox.mass"] == UNSPRUNG


def test_unknown_override_is_named():
    with pytest.raises(ValueError, match="carbody.mas"):
        trailer_values(carbody__mas=1.0)


def test_topology_is_the_papers_11_bodies():
    vehicle, params = trailer()
    names = vehicle.system.body_names
    assert len(names) == 11
    assert sum(n.startswith("wheelset") for n in names) == 4
    assert sum(n.startswith("axlebox") for n in names) == 4
    assert sum(n.startswith("bogie") for n in names) == 2
    # 11 normalisations + 4 revolute joints x 5 equations
    assert vehicle.system.n_constraints == 11 + 4 * 5
    assert params.system.forces["bushing"].stiffness.shape == (12, 6)
    assert [names[i] for i in vehicle.wheelsets] == [f"wheelset_{k}" for k in range(1, 5)]


@pytest.fixture(scope="module")
def straight_run():
    vehicle, params = trailer()
    options = SolverOptions(rtol=1e-3, atol=1e-6, n_outputs=21)
    result = simulate(vehicle, straight_track(120.0), params, 1.0, 18.3, 2e-3, options=options)
    return vehicle, params, result


def test_run_with_misalignment_is_successful(straight_run):
    _, _, result = straight_run
    assert result.status == "successful"
    assert bool(np.all(result.valid))
    for leaf in jax.tree.leaves((result.q, result.qdot, result.wheels)):
        assert np.all(np.isfinite(np.asarray(leaf, dtype=float)))
    assert float(np.max(result.constraint_violation)) < 1e-7  # [m], rtol 1e-3
    lateral = np.asarray(result.wheelset_lateral)
    assert np.allclose(lateral[0], 2e-3, atol=1e-6)
    assert np.max(np.abs(lateral[-1])) < 2e-3  # gravitational stiffness pulls it back


def test_wheel_loads_are_weight_over_8(straight_run):
    _, _, result = straight_run
    # the start: every wheel carries W/8 although the vehicle is 2 mm off centre
    assert np.allclose(result.wheels.vertical_force[0], WEIGHT / 8, rtol=1e-3)
    q = np.asarray(result.wheels.vertical_force[-1])  # (4 wheelsets, 2 wheels)
    assert np.allclose(q, WEIGHT / 8, rtol=0.01)
    assert abs(q.sum() / WEIGHT - 1.0) < 2e-3


def test_suspension_carries_the_static_loads(straight_run):
    vehicle, params, result = straight_run
    q = np.asarray(result.q[-1]).reshape(-1, 7)
    bushing = params.system.forces["bushing"]
    group = next(g for g in vehicle.system.force_groups if g.kind == "bushing")
    loads = {"primary": (CARBODY + 2 * BOGIE) * G / 8, "secondary": CARBODY * G / 4}
    stiffness = {"primary": PRIMARY_KZ, "secondary": SECONDARY_KZ}
    for k, name in enumerate(group.names):
        element = jax.tree.map(lambda x: x[k], bushing)
        s = element_deformation("bushing", q[group.body_i[k]], q[group.body_j[k]], element)
        force = np.asarray(element.stiffness * s + element.preload)
        kind = name.split("_")[0]
        assert abs(-force[2] / loads[kind] - 1.0) < 0.01, name
        # static deflection implied by the parameter file: load / k
        deflection = -float(element.preload[2]) / float(element.stiffness[2]) - float(s[2])
        assert abs(deflection / (loads[kind] / stiffness[kind]) - 1.0) < 0.01, name
    # the carbody stays where the equilibrium put it
    assert np.max(np.abs(np.asarray(result.qdot)[:, 2])) < 2e-3


def test_a_derailment_stops_the_run_and_keeps_the_results_so_far(straight_run):
    vehicle, params, first = straight_run
    # Restart from the first run's state when every wheelset is within 0.9 mm of the
    # centreline, with a lateral limit of 0.9 mm: the swing that follows (to 1.1 mm on
    # the other side) must stop the run.
    limit = 0.9e-3
    lateral = np.max(np.abs(np.asarray(first.wheelset_lateral)), axis=1)  # (T,)
    start = int(np.argmax(lateral < limit))
    assert 0 < start and limit < np.max(lateral[start:])
    options = SolverOptions(rtol=1e-3, atol=1e-6, n_outputs=21)
    result = simulate(vehicle, straight_track(120.0), params, 1.0, 18.3, 2e-3, options=options,
                      limits=DerailmentLimits(lateral=limit),
                      initial=(first.q[start], first.qdot[start]))
    assert float(result.compile_time_s) == 0.0  # new limits and start: same program
    assert result.status == "derailed"
    valid = np.asarray(result.valid)
    stop = int(np.argmin(valid))
    assert stop >= 1 and not np.any(valid[stop:])
    # the results so far follow the first run (shifted by the restart time)
    assert np.allclose(result.wheelset_lateral[:stop],
                       first.wheelset_lateral[start:start + stop], atol=2e-6)
    assert np.max(np.abs(lateral[start:start + stop])) <= limit
    assert np.max(np.abs(lateral[start:start + stop + 1])) > limit
    assert np.all(np.isnan(np.asarray(result.wheels.normal_force[stop:])))
