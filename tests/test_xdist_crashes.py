"""tests/xdist_crashes.py: a worker that dies under ``--dist loadfile`` neither hangs the
run nor loses tests; the test it died in runs once more, and fails if it dies again.
Each case is a small project of files run by pytest with two workers in a subprocess."""

import os
import subprocess
import sys
from pathlib import Path

PLUGIN = Path(__file__).with_name("xdist_crashes.py")

# the first test of test_e dies the first time it runs (SIGABRT, as in a native library)
DIES_ONCE = """
import os
from pathlib import Path


def test_dies_once():
    mark = Path({mark!r})
    if not mark.exists():
        mark.write_text("died")
        os.abort()


def test_after_it():
    pass
"""

DIES_ALWAYS = """
import os


def test_dies_always():
    os.abort()


def test_after_it():
    pass
"""

PASSING = """
def test_one():
    pass


def test_two():
    pass
"""

LONE = """
def test_lone():
    pass
"""


def _run(tmp_path, dying):
    project = tmp_path / "project"
    project.mkdir()
    (project / "pytest.ini").write_text("[pytest]\n")
    # the dying file last, so that the worker has finished files when it dies: the stock
    # scheduler then hands them out again, empty, and the run hangs
    for name, text in (("test_a.py", PASSING), ("test_b.py", LONE), ("test_c.py", PASSING),
                       ("test_d.py", LONE), ("test_e.py", dying)):
        (project / name).write_text(text)
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(PLUGIN.parent),
                                                       env.get("PYTHONPATH")]))
    done = subprocess.run([sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadfile",
                           "-p", PLUGIN.stem, "-p", "no:cacheprovider", "-q"],
                          cwd=project, env=env,
                          capture_output=True, text=True, timeout=120)
    return done.returncode, done.stdout + done.stderr


def test_a_test_whose_worker_dies_once_runs_again_and_the_run_ends(tmp_path):
    code, output = _run(tmp_path, DIES_ONCE.format(mark=str(tmp_path / "died")))
    assert code == 0, output
    assert "8 passed, 1 rerun" in output, output
    assert "crashed while running 'test_e.py::test_dies_once'" in output, output


def test_a_test_whose_worker_dies_twice_fails_and_the_run_ends(tmp_path):
    code, output = _run(tmp_path, DIES_ALWAYS)
    assert code == 1, output
    assert "1 failed, 7 passed, 1 rerun" in output, output
