"""Bad command-line inputs: exit status 2 and an error naming the flag, what is allowed
and what was given, before anything compiles."""

from pathlib import Path

import pytest

from jaxrail.cli import main

SCENARIO = str(Path(__file__).parent / "data" / "wheelset-straight.toml")
BAD_INPUTS = [
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=-20:-10"],
     "--vary speed: a drawn value must be within [0.1, 160] m/s"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "friction=-0.3,-0.1"],
     "--vary friction: a drawn value must be within [0.01, 1.5] -, got -0."),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "misalignment=0:0.05"],
     "--vary misalignment: a drawn value must be within [-0.035, 0.035] m"),
    (["montecarlo", SCENARIO, "--samples", "4", "--duration", "nan"],
     "--duration must be within [0.0001, 3600] s, got nan"),
    (["simulate", SCENARIO, "--duration", "inf"],
     "--duration must be within [0.0001, 3600] s, got inf"),
    (["simulate", SCENARIO, "--duration", "3000"],
     "300001 output times (the trailer's results alone 1.14 GB); at most 200001"),
]


@pytest.mark.parametrize("argv, message", BAD_INPUTS)
def test_bad_command_lines_are_named(argv, message, capsys):
    assert main(argv + ["--quiet"]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


@pytest.mark.parametrize("outputs, message", [
    (["--summary", "{file}/s.json"], "--summary {file}/s.json: cannot make the folder"),
    (["--plots", "{file}"], "--plots {file}: cannot make the folder"),
    (["--out", "{folder}"], "--out {folder}: is a folder, not a file"),
])
def test_output_paths_are_checked_before_the_run(outputs, message, tmp_path, capsys):
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    names = {"file": str(blocker), "folder": str(tmp_path)}
    argv = ["simulate", SCENARIO, "--duration", "0.01", "--quiet",
            "--out", str(tmp_path / "run.h5")] + [x.format(**names) for x in outputs]
    assert main(argv) == 3
    assert message.format(**names) in capsys.readouterr().err
    assert not (tmp_path / "run.h5").exists()  # nothing ran, nothing was written
