"""Without float64 the library refuses to build profiles and tracks and to compute creep
forces (docs/design.md §8)."""

import os
import subprocess
import sys

SCRIPT = """
import jaxrail.profiles as profiles
from jaxrail.contact import polach
from jaxrail.track import straight_track
for build in (profiles.s1002, profiles.uic60, lambda: straight_track(10.0),
              lambda: polach(1e4, 0.3, 0.005, 0.004, 0.001, 0.0, 0.0)):
    try:
        build()
    except RuntimeError as error:
        assert "float64" in str(error), error
    else:
        raise SystemExit("built in float32")
print("refused")
"""


def test_constructors_refuse_float32():
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          env={**os.environ, "JAX_ENABLE_X64": "0"}, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "refused"
