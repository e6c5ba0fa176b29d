"""The residual functions of a fit (and so its compiled programs) are shared by fits of
the same model, and only by them: two contact tables of the same grid are different
models, whatever the contact model's name."""

from pathlib import Path

import numpy as np

from jaxrail.contact.table import Axis, ContactTable, TableGrid
from jaxrail.contact.table.grid import FIELDS
from jaxrail.identification import Measurements, _residual_functions
from jaxrail.scenarios import load_scenario
from jaxrail.simulation import SolverOptions
from jaxrail.vehicles.loads import TableContact

GRID = TableGrid(lateral=Axis.span(-0.001, 0.001, 1e-3), yaw=Axis.span(0.0, 0.0, 1.0),
                 roll=Axis.span(0.0, 0.0, 1.0))


def _table_model(values):
    return TableContact(ContactTable(values, GRID, (0, 0), 0.46))


def test_fits_share_functions_only_for_the_same_table():
    scenario = load_scenario(Path(__file__).parents[1] / "data" / "wheelset-straight.toml")
    vehicle, params, track = scenario.build()
    t = np.linspace(0.0, 0.05, 6)
    measurements = Measurements(t, ("wheelset_lateral_1",), np.zeros((6, 1)), [1e-4])
    values = np.random.default_rng(0).normal(size=(2, 5, 1, 1, 6, 3, len(FIELDS)))
    other = values.copy()
    other[1, 2, 0, 0, 3, 0, 0] += 1e-6  # one coefficient of one node

    def functions(model):
        common = dict(speed=10.0, misalignment=0.0, duration=0.05,
                      options=SolverOptions(fixed_step=1e-3), cutoff=None,
                      contact_model=model)
        return _residual_functions(vehicle, params, track, ("friction",), measurements,
                                   common)

    first = functions(_table_model(values))
    assert functions(_table_model(values.copy())) is first  # equal content: shared
    assert functions(_table_model(other)) is not first  # another table, same name
