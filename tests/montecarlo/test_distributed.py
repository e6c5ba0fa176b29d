"""Monte Carlo across processes for real: `jaxrail montecarlo --distributed` in two
local processes (a local coordinator, one CPU device each) gives the table of the same
samples run in one process, and only process 0 writes the files; process 1 comes to
the gather of the results 40 s after process 0 (Gloo's set-up gives up after 30 s
unless the processes first meet at the coordination service's barrier). The
one-process run starts while process 1 waits, on the core the two would leave idle."""

import csv
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

SCENARIO = Path(__file__).parents[1] / "data" / "wheelset-straight.toml"


def _free_port():
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


# `jaxrail` with the compile of the study's program made 40 s longer on process 1,
# which first creates the file $LATE_MARK
LATE = """
import os, sys, time
from pathlib import Path
import jax
import jaxrail.montecarlo.batch as batch
from jaxrail.cli import main

compile_program = batch.compile_program


def late_compile(*args, **kwargs):
    out = compile_program(*args, **kwargs)
    if jax.process_index() == 1:
        Path(os.environ["LATE_MARK"]).touch()
        time.sleep(40.0)
    return out


batch.compile_program = late_compile
sys.exit(main(sys.argv[1:]))
"""


def _command(where, *extra, program=("-m", "jaxrail.cli")):
    return [sys.executable, *program, "montecarlo", str(SCENARIO), "--samples",
            "4", "--duration", "0.05", "--vary", "speed=8:12", "--vary",
            "misalignment=0:0.003", "--quiet", "--out", str(where / "table.csv"),
            "--summary", str(where / "summary.json"), *extra]


def _rows(path):
    with open(path) as stream:
        return list(csv.DictReader(stream))


def test_two_processes_give_the_one_process_table(tmp_path):
    (tmp_path / "one").mkdir()
    (tmp_path / "two").mkdir()
    coordinator = f"localhost:{_free_port()}"
    mark = tmp_path / "late"
    runs = [subprocess.Popen(_command(tmp_path / "two", "--distributed", "--coordinator",
                                      coordinator, "--num-processes", "2", "--process-id",
                                      str(k), program=("-c", LATE)),
                             env=dict(os.environ, LATE_MARK=str(mark)),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for k in (0, 1)]
    outputs = []
    try:
        deadline = time.monotonic() + 600
        while not mark.exists() and runs[1].poll() is None and time.monotonic() < deadline:
            time.sleep(0.5)
        runs.append(subprocess.Popen(_command(tmp_path / "one"), stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True))
        for run in runs:
            outputs.append(run.communicate(timeout=600))
    finally:
        for run in runs:
            run.kill()
    for run, (_, err) in zip(runs, outputs):
        assert run.returncode == 0, err[-2000:]
    first, second, single = (err for _, err in outputs)
    assert "on 2 device(s)" in first and "on 1 device(s)" in single
    assert "wrote" in first and "wrote" not in second  # process 0 writes, once
    two, one = _rows(tmp_path / "two" / "table.csv"), _rows(tmp_path / "one" / "table.csv")
    assert len(two) == len(one) == 4 and two[0].keys() == one[0].keys()
    # The two processes integrate 2 samples each, the one process 4 together: XLA's
    # programs for the two batch sizes round differently, and the stiff contact turns
    # positions equal to 1e-12 m into forces that differ by up to 3e-7 relative (the
    # same 4 samples in one process in chunks of 4 and of 2, on 2026-12-01). Rows out of
    # place or results gathered wrongly differ by more than 10 % (speed 8 to 12 m/s).
    for key in one[0]:
        a, b = [r[key] for r in one], [r[key] for r in two]
        try:
            np.testing.assert_allclose(np.array(b, float), np.array(a, float), rtol=1e-6,
                                       atol=1e-12, err_msg=key)
        except ValueError:  # a text column
            assert a == b, key
    assert (tmp_path / "two" / "summary.json").exists()
