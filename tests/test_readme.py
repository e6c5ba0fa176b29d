"""The README's contact-search example runs as written in a fresh process (its
simulation example runs in tests/vehicles/test_trailer.py, reusing that module's
compiled programs), and ``import jaxrail`` exposes the names a user starts from."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).parents[1] / "README.md"
EXAMPLES = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


def test_the_readme_has_a_simulation_and_a_search_example():
    assert len(EXAMPLES) == 2
    assert "run_scenario" in EXAMPLES[0] and "search_wheelset" in EXAMPLES[1]


def test_readme_search_example_runs():
    done = subprocess.run([sys.executable, "-c", EXAMPLES[1]], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]


def test_top_level_names():
    import jaxrail

    for name in jaxrail.__all__:
        assert getattr(jaxrail, name) is not None, name
    assert jaxrail.run_scenario.__module__ == "jaxrail.scenarios"
    assert jaxrail.simulate.__module__ == "jaxrail.simulation.run" and callable(jaxrail.simulate)
    assert jaxrail.identify.__module__ == "jaxrail.identification" and callable(jaxrail.identify)


SUBPACKAGES = ("contact", "geometry", "identification", "montecarlo", "multibody", "plots",
               "profiles", "scenarios", "track", "vehicles")


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_every_subpackage_declares_its_public_names(name):
    import importlib

    module = importlib.import_module(f"jaxrail.{name}")
    assert module.__all__ and len(set(module.__all__)) == len(module.__all__)
    assert all(getattr(module, n, None) is not None for n in module.__all__), name
