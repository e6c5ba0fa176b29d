"""A route's runs split over two host devices (``route_wear(devices=...)``, ``jaxrail
wear --host-devices``): three sections, padded to four (the third runs beside a copy of
itself), give each section's wear as the three run in one batch on one device.

Not to rounding: a batch's members keep their own step-size controllers, but the
batch they share changes their steps at about 1e-6 (the Monte Carlo batch against its
samples alone, tests/montecarlo/test_batch.py), and the KTH map's edges (a sevenfold
step blended over +-5 %) amplify that in the wear to about 4e-4. The sections'
misalignments make their wear differ by 10 % or more, so a section's wear given to
another, or a copy's, fails by far more than the tolerance."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from jaxrail._devices import host_device_environment

SCENARIO = Path(__file__).parents[1] / "data" / "wheelset-straight.toml"
BATCH_RTOL = 2e-3  # another batch around each run: see the module docstring


def test_sections_split_over_two_devices_give_each_its_own_wear(tmp_path):
    out = tmp_path / "devices.json"
    script = textwrap.dedent(f"""
        import json
        import numpy as np
        import jax
        from jaxrail import enable_float64
        enable_float64()
        from jaxrail.wear.evolution import route_wear
        from jaxrail.wear.route import parse_route
        assert len(jax.devices()) == 2, jax.devices()
        sections = "".join(f'''
        [[sections]]
        weight = 1.0
        speed = 10.0
        misalignment = {{m}}
        ''' for m in (0.001, 0.002, 0.003))
        route = parse_route(f'''
        name = "three-straights"
        scenario = "{SCENARIO}"
        duration = 0.8
        settle = 0.0
        ''' + sections)
        split = route_wear(route, contact="online")
        one = route_wear(route, contact="online", devices=jax.devices()[:1])
        json.dump({{"split": split.sections_volume_per_km.tolist(),
                   "one": one.sections_volume_per_km.tolist(),
                   "completed": split.completed.tolist()}}, open({str(out)!r}, "w"))
    """)
    env = dict(os.environ)
    env.update(host_device_environment(2, env))
    subprocess.run([sys.executable, "-c", script], env=env, check=True, timeout=1500)
    done = json.loads(out.read_text())
    import numpy as np

    split, one = np.array(done["split"]), np.array(done["one"])
    assert all(done["completed"]) and split.shape == one.shape == (3, 1, 2)
    total = one.sum(axis=(1, 2))
    assert np.all(total > 0.0)
    assert np.min(np.abs(total[:, None] - total[None, :]) + np.eye(3)) > 0.1 * total.min()
    np.testing.assert_allclose(split, one, rtol=BATCH_RTOL)
