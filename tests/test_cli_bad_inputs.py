"""Bad command-line inputs: exit status 2 and an error naming the flag, what is allowed
and what was given, before anything compiles."""

from pathlib import Path

import pytest

from jaxrail.cli import main

DATA = Path(__file__).parent / "data"
SCENARIO = str(DATA / "wheelset-straight.toml")
ROUTES = DATA / "routes"
RESULTS_FILE = "expected an HDF5 results file written by `jaxrail simulate --out`"
BAD_INPUTS = [
    (["assess", SCENARIO], f"{SCENARIO}: not an HDF5 file; {RESULTS_FILE}"),
    (["assess", "nofile.h5"], f"nofile.h5: no such file; {RESULTS_FILE}"),
    (["assess", str(DATA)], f"{DATA}: is a folder; {RESULTS_FILE}"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=-20:-10"],
     "--vary speed: a drawn value must be within [0.1, 160] m/s"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "friction=-0.3,-0.1"],
     "--vary friction: a drawn value must be within [0.01, 1.5] -, got -0."),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "misalignment=0:0.05"],
     "--vary misalignment: a drawn value must be within [-0.035, 0.035] m"),
    (["montecarlo", SCENARIO, "--samples", "4", "--duration", "nan"],
     "--duration must be within [0.0001, 3600] s, got nan"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "contact_stiffness=-1:2"],
     "--vary contact_stiffness: a drawn value must be within [0.01, 100] -, got -0."),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "wheelbase=0:30"],
     "--vary wheelbase: a drawn value must be within [0.5, 5] m"),
    (["montecarlo", SCENARIO, "--samples", "100000000"],
     "give at least one input to vary (--vary): runs of the same inputs are one run"),
    (["montecarlo", SCENARIO, "--samples", "100000000", "--vary", "speed=10:20"],
     "100000000 samples: at most 1000000 in one study"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=20:10"],
     "--vary 'speed=20:10': speed: a uniform range needs lo <= hi, got (20.0, 10.0)"),
    (["montecarlo", SCENARIO, "--samples", "0", "--vary", "speed=10:20"],
     "--samples must be >= 1, got 0"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=a:b"],
     "--vary 'speed=a:b': could not convert string to float: 'a'"),
    (["geometry", "--shift-step", "0"], "--shift-step must be > 0, got 0.0"),
    (["geometry", "--shift-from", "5", "--shift-to", "-5"],
     "--shift-from (5.0) must be less than --shift-to (-5.0)"),
    (["geometry", "--wheel", "nofile.prw"], "--wheel: unknown profile 'nofile.prw'"),
    (["geometry", "--inclination", "1:30"], "--inclination: uic60: unknown inclination '1:30'"),
    (["geometry", "--yaw-per-shift", "nan"], "--yaw-per-shift must be finite, got nan"),
    (["profile", "uic60", "--gauge", "nan"],
     "--gauge must be a track gauge within [600, 1700] mm, got nan"),
    (["tables", "build", "nofile.toml"], "unknown scenario 'nofile.toml'"),
    (["montecarlo", SCENARIO, "--samples", "4", "--vary", "speed=10:20", "--seed", "-1"],
     "--seed must be >= 0, got -1"),
    (["profile", "uic60", "--points", "0"], "--points must be within [2, 100001], got 0"),
    (["profile", "uic60", "--points", "100000000"],
     "--points must be within [2, 100001], got 100000000"),
    (["simulate", SCENARIO, "--duration", "inf"],
     "--duration must be within [0.0001, 3600] s, got inf"),
    (["simulate", SCENARIO, "--duration", "3000"],
     "300001 output times (the trailer's results alone 1.14 GB); at most 200001"),
    (["stability", "suspended-wheelset", "--speeds", "80"],
     "--speeds '80': give LO:HI in m/s with 0 < LO < HI"),
    (["stability", "suspended-wheelset", "--speeds", "90:40"],
     "--speeds '90:40': give LO:HI in m/s with 0 < LO < HI"),
    (["stability", "suspended-wheelset", "--points", "1"], "--points 1: need at least 2"),
    (["stability", "nofile.toml"], "unknown scenario 'nofile.toml'"),
    (["stability", "suspended-wheelset", "--nonlinear", "95:65"],
     "--nonlinear '95:65': give LO:HI in m/s with 0 < LO < HI"),
    (["stability", "suspended-wheelset", "--nonlinear", "65:95", "--ramp-rate", "0"],
     "--ramp-rate 0 and --resolution 0.5 must be > 0"),
    (["stability", "suspended-wheelset", "--curve", "-300"],
     "--curve '-300': give RADIUS[:CANT] in m with RADIUS > 0"),
    (["stability", "suspended-wheelset", "--curve", "3000:0.1", "--nonlinear", "65:95"],
     "--nonlinear runs on straight track only: leave out --curve"),
    (["wear", str(ROUTES / "no-sections.toml")],
     "no-sections.toml: the route has no sections (give [[sections]] tables)"),
    (["wear", str(ROUTES / "negative-weight.toml")],
     "sections[0]: weight must be >= 0, got -1.0"),
    (["wear", str(ROUTES / "zero-weights.toml")],
     "the sections' weights sum to 0; they must sum to a positive number"),
    (["wear", str(ROUTES / "unknown-model.toml")],
     "unknown wear model 'archard': use one of archard-kth, usfd"),
    (["wear", str(ROUTES / "map-out-of-range.toml")],
     "[wear]: wear model archard-kth: k4 = 0.05 lies outside the KTH map's published "
     "range [0.03, 0.04]"),
    (["wear", "curved-route", "--distance", "1000", "--step", "2000"],
     "--step 2000 km is larger than --distance 1000 km"),
    (["wear", "nofile.toml"], "unknown route 'nofile.toml': use one of straight-route, "
                              "curved-route, main-line-route or a .toml file"),
    (["wear", "straight-route", "--host-devices", "0"], "host devices: need a count >= 1"),
]


@pytest.mark.parametrize("argv, message", BAD_INPUTS)
def test_bad_command_lines_are_named(argv, message, capsys):
    quiet = ["--quiet"] if argv[0] in ("simulate", "montecarlo", "tables", "stability",
                                       "wear") else []
    assert main(argv + quiet) == 2
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


@pytest.mark.parametrize("argv, message", [
    (["geometry", "--gauge", "1"], "--gauge must be a track gauge within [600, 1700] mm, got 1.0"),
    (["geometry", "--gauge", "1e7"], "--gauge must be a track gauge within [600, 1700] mm"),
    (["geometry", "--gauge", "nan"], "--gauge must be a track gauge within [600, 1700] mm"),
    (["geometry", "--shift-from", "-250", "--shift-to", "250"],
     "--shift-from must be within [-25, 25] mm"),
    (["geometry", "--shift-step", "1e-6"], "gives 20000001 shifts in [-10.0, 10.0] mm"),
    (["profile", "s1002", "--gauge", "-1435", "--plot", "p.png"],
     "--gauge must be a track gauge within [600, 1700] mm, got -1435.0"),
])
def test_bad_geometry_and_profile_options_are_named(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


HEADER = "distance [m],alignment [mm],vertical level [mm],cross level [mm],gauge deviation [mm]"


def measured_rows(length_m, step_m=0.25, vertical_mm="1.0"):
    """Rows of a measured irregularity file from 0 to ``length_m`` [m]; the vertical
    level of the third row is ``vertical_mm`` (text), the rest 0.5 mm."""
    rows = [f"{k * step_m:g},0.5,{vertical_mm if k == 2 else '0.5'},0.5,0.5"
            for k in range(round(length_m / step_m) + 1)]
    return "\n".join([HEADER, *rows]) + "\n"


@pytest.mark.parametrize("text, message", [
    (measured_rows(20.0, vertical_mm="x"),
     "line 4: column 'vertical level [mm]': 'x' is not a number"),
    (measured_rows(20.0, vertical_mm="900"), "a value of 900 mm: more than 500 mm"),
    (measured_rows(20.0).replace("\n0.5,", "\n0.6,", 1), "unequal spacing"),
    (HEADER.replace("gauge", "gage") + "\n", "missing column(s) gauge deviation [mm]"),
    # well formed, but the run's wheelset goes from 5 to 6 m: the file ends at 3 m
    (measured_rows(3.0), "covers s = 0 to 3 m but the run's wheelsets go from 5.0 to 6.0 m"),
])
def test_a_bad_measured_irregularity_file_stops_simulate_before_compiling(text, message,
                                                                          tmp_path, capsys):
    (tmp_path / "line.csv").write_text(text)
    scenario = tmp_path / "measured.toml"
    scenario.write_text(Path(SCENARIO).read_text() + '\n[irregularities]\nfile = "line.csv"\n')
    assert main(["simulate", str(scenario), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert message in err and "line.csv" in err and "Traceback" not in err
    assert "compiling" not in err
