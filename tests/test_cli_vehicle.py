"""``jaxrail vehicle list`` and ``jaxrail vehicle show``: the built-in vehicles, and an
unknown vehicle named. The trailer's report is checked in
tests/stability/test_standing.py, beside the programs it shares."""

from jaxrail.cli import main
from jaxrail.vehicles import vehicle_names


def test_list_names_each_built_in_vehicle_with_its_description(capsys):
    assert main(["vehicle", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == vehicle_names()
    trailer = next(line for line in lines if line.startswith("trailer "))
    assert "11-body trailer" in trailer


def test_an_unknown_vehicle_is_named_with_the_built_in_ones(tmp_path, capsys):
    report = tmp_path / "report.json"
    assert main(["vehicle", "show", "no-such-vehicle", "--json", str(report)]) == 2
    error = capsys.readouterr().err
    assert ("jaxrail vehicle: error: no vehicle file 'no-such-vehicle': give a path or a "
            f"built-in name ({', '.join(vehicle_names())})") in error
    assert not report.exists()
