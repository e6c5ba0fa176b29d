"""The built-in routes (jaxrail/wear/data): each reads, is named as it is called, and
its description names what its sections are (their speeds and radii), so the text a
user reads stays true with the file."""

import pytest

from jaxrail.wear.route import BUILTIN, load_route


@pytest.mark.parametrize("name", BUILTIN)
def test_builtin_route_reads_and_its_description_names_its_sections(name):
    route = load_route(name)
    assert route.name == name
    assert abs(route.shares().sum() - 1.0) < 1e-12
    for section in route.sections:
        assert f"{section.speed:g} m/s" in route.description \
            or f"{section.speed:g}," in route.description \
            or f"{section.speed:g} and" in route.description, (name, section.speed)
        if section.curved:
            assert f"{section.radius:g}" in route.description, (name, section.radius)
