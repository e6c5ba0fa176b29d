"""Batched Monte Carlo: many runs of one scenario over drawn speeds, misalignments and
parameter values, as one vmapped simulation sharded across the local devices.

``run_montecarlo(scenario, [parse_variation("speed=10:25"), ...], n=200, seed=1)``
draws the samples (:mod:`.sampling`), runs them in chunks (:mod:`.batch`) and returns a
:class:`MonteCarlo` whose ``table`` has one row per sample: its inputs and the
quantities of :mod:`.summary` (maximum lateral displacement, Y/Q against Nadal, Sum Y
against Prud'homme, maximum normal force, flange contact fraction, wear number,
status). ``write_table`` writes it as CSV or Parquet; ``study_statistics`` gives the
study's facts and the min, median and max of every quantity over the successful samples
(:mod:`.statistics`).
"""

import dataclasses

import numpy as np

from .._ranges import within
from ..scenarios import checks
from ..vehicles.parameters import (PARAMETERS, check_contact_follows, get_values,
                                   vehicle_parameters)
from .batch import run_chunks
from .checkpoint import Checkpoint, shared_rows, study_key
from .sampling import DESIGNS, Variation, check_names, draw, parse_variation
from .statistics import column_statistics, study_statistics, successful
from .summary import sample_row
from .table import read_table, write_table

__all__ = ["DESIGNS", "MAX_SAMPLES", "MonteCarlo", "Variation", "check_samples",
           "column_statistics", "draw", "parse_variation", "read_table", "run_montecarlo",
           "run_samples", "study_statistics", "successful", "write_table"]


@dataclasses.dataclass
class MonteCarlo:
    """Result of :func:`run_montecarlo`: ``table`` {column: array} (inputs first),
    ``samples`` {input: array}, ``compile_time_s``, ``run_time_s`` (all chunks, without
    compiling), ``chunk`` (samples per compiled call), ``devices``, ``seed``, and
    ``results`` (the batched SimulationResult of every sample as NumPy, when kept)."""

    table: dict
    samples: dict
    compile_time_s: float
    run_time_s: float
    chunk: int
    devices: int
    seed: int | None = None
    results: object = None

    @property
    def statuses(self) -> dict:
        """{status: count}."""
        names, counts = np.unique(self.table["status"], return_counts=True)
        return {str(k): int(v) for k, v in zip(names, counts)}

    def throughput(self, duration: float) -> float:
        """Simulated seconds per wall second (run time, without compiling)."""
        return len(self.table["status"]) * duration / self.run_time_s


MAX_SAMPLES = 1_000_000
"""Most samples of one study (its table alone is then about 0.2 GB)."""
MAX_SEED = 2 ** 31 - 1
"""Largest irregularity seed."""


def check_samples(samples: dict, where: str, key: str, known=PARAMETERS) -> None:
    """Every value of ``samples`` {input: array} within the range of its input: the
    scenario's (:data:`jaxrail.scenarios.checks.RANGES`) for speed and misalignment,
    the parameter's (``known``: :mod:`jaxrail.vehicles.parameters`) for the others. The
    error names ``where`` (with ``{name}`` for the input) and ``key``."""
    for name, values in samples.items():
        if name in ("speed", "misalignment", "irregularity_scale"):
            low, high, unit = checks.RANGES[name]
        elif name == "irregularity_seed":
            low, high, unit = 0.0, float(MAX_SEED), "-"
        elif name in known:
            (low, high), unit = known[name].range, known[name].unit
        else:
            continue
        values = np.atleast_1d(np.asarray(values, dtype=float))
        bad = ~(np.isfinite(values) & (values >= low) & (values <= high))
        if bad.any():  # the first value out of range, named
            within(values[bad][0], low, high, unit, f"{where.format(name=name)}: {key}")


def _irregularity_inputs(scenario, track, samples, n):
    """``(seed (n,), scale (n,), realise)`` of the samples' irregularities: the drawn seeds
    (rounded down) and scales, else the scenario's; ``realise`` the scenario's spectrum
    over the design track when seeds are drawn (None otherwise)."""
    spec = scenario.irregularities
    drawn = [k for k in ("irregularity_seed", "irregularity_scale") if k in samples]
    if drawn and spec is None:
        raise ValueError(f"--vary {drawn[0]}: the scenario {scenario.name!r} has no "
                         "[irregularities] to vary")
    if "irregularity_seed" in samples and spec.source != "spectrum":
        raise ValueError(f"--vary irregularity_seed: the scenario's irregularity is a "
                         f"{spec.source}, not a spectrum with realisations")
    default_seed = 0 if spec is None else spec.seed
    default_scale = 1.0 if spec is None else spec.scale
    seed = np.floor(np.broadcast_to(np.asarray(samples.get("irregularity_seed", default_seed),
                                               np.float64), (n,)))
    scale = np.broadcast_to(np.asarray(samples.get("irregularity_scale", default_scale),
                                       np.float64), (n,))
    realise = None
    if "irregularity_seed" in samples:
        length = spec.length if spec.length is not None else float(track.total_length)
        realise = dataclasses.replace(spec, length=length)
    return seed, scale, realise


def run_samples(scenario, samples: dict, *, duration=None, chunk=None, devices=None,
                progress=False, keep_results=False, built=None, contact=None,
                checkpoint=None, overwrite=False) -> MonteCarlo:
    """Run ``scenario`` once per sample: ``samples`` {input: array (N,)} with inputs
    ``speed`` [m/s], ``misalignment`` [m], ``irregularity_seed``, ``irregularity_scale``
    and parameter names (others keep the scenario's values). ``duration`` [s] overrides
    the scenario's; ``devices``: the devices to shard over (default all); ``built``: the
    scenario's ``build()`` output, to reuse; ``contact``: ``"online"`` or ``"table"``
    (default the scenario's mode). ``checkpoint``: a file (:mod:`.checkpoint`) that keeps
    every finished chunk's rows, written whole after each chunk; a second call with the
    same study resumes from it (another study is refused unless ``overwrite``)."""
    import jax

    vehicle, params, track = scenario.build() if built is None else built
    known = vehicle_parameters(vehicle, params)
    check_names(samples, known)
    # a misalignment beyond the lateral limit is a start that ends "derailed" at once
    check_samples({k: v for k, v in samples.items() if k != "misalignment"},
                  "samples[{name!r}]", "a value", known)
    lengths = {k: len(np.atleast_1d(v)) for k, v in samples.items()}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"samples: every input needs the same number of values, got {lengths}")
    n = next(iter(lengths.values()), 1)
    duration = scenario.duration if duration is None else float(duration)
    options = scenario.solver_options(duration=duration)
    names = tuple(k for k in samples if k in known)
    check_contact_follows(names, scenario.contact if contact is None else contact)
    speed = np.broadcast_to(np.asarray(samples.get("speed", scenario.speed), np.float64), (n,))
    shift = np.broadcast_to(np.asarray(samples.get("misalignment", scenario.misalignment),
                                       np.float64), (n,))
    scenario.check_irregularity_covers(track, params, duration, speed=np.max(speed))
    seed, scale, realise = _irregularity_inputs(scenario, track, samples, n)
    values = np.stack([np.asarray(samples[k], np.float64) for k in names], axis=1) if names \
        else np.zeros((n, 0))
    friction = (np.asarray(samples["friction"], np.float64) if "friction" in samples
                else np.full(n, float(get_values(vehicle, params, ("friction",))[0])))
    devices = jax.devices() if devices is None else list(devices)
    rows, kept = [None] * n, []
    saved = None
    if checkpoint is not None:
        study = study_key(scenario, samples, duration, contact, chunk)
        saved = Checkpoint.open(checkpoint, study, n, overwrite)
    for i, row in shared_rows({} if saved is None else saved.rows).items():
        rows[i] = row
    done = np.array([row is not None for row in rows])
    if keep_results and np.any(done):
        raise ValueError("keep_results needs every sample run in this call; a checkpoint "
                         f"{checkpoint} holds finished samples")

    def collect(start, stop, result):
        for i in range(start, stop):
            one = jax.tree.map(lambda x: x[i - start], result)
            rows[i] = sample_row(one, friction[i], speed[i],
                                 vehicle.system.body_names)
        if saved is not None:
            saved.add({i: rows[i] for i in range(start, stop)})
        if keep_results:
            kept.append(result)

    model = scenario.contact_model(vehicle, params, track, contact, progress)
    compile_s, run_s, chunk = run_chunks((vehicle, params, track, model),
                                         (values, speed, shift, seed, scale), chunk, devices,
                                         progress=progress, on_chunk=collect, done=done,
                                         names=names, duration=duration, options=options,
                                         realise=realise)
    table = {"sample": np.arange(n), "speed": speed.copy(), "misalignment": shift.copy()}
    if scenario.irregularities is not None:
        table |= {"irregularity_seed": seed.copy(), "irregularity_scale": scale.copy()}
    table |= {k: np.asarray(samples[k], np.float64) for k in names}
    for key in rows[0]:
        table[key] = np.array([row[key] for row in rows])
    results = (jax.tree.map(lambda *xs: np.concatenate(xs), *kept) if keep_results else None)
    return MonteCarlo(table, dict(samples), compile_s, run_s, chunk, len(devices),
                      results=results)


def run_montecarlo(scenario, variations, n: int, *, seed: int = 0, design: str = "latin",
                   **kwargs) -> MonteCarlo:
    """Draw ``n`` samples of ``variations`` (:class:`Variation` or their text) with
    ``seed`` and ``design`` (:func:`.sampling.draw`) and run them (:func:`run_samples`,
    whose keyword arguments pass through)."""
    variations = [parse_variation(v) if isinstance(v, str) else v for v in variations]
    if not variations:
        raise ValueError("give at least one input to vary (--vary): runs of the same "
                         "inputs are one run")
    if n > MAX_SAMPLES:
        raise ValueError(f"{n} samples: at most {MAX_SAMPLES} in one study")
    samples = draw(variations, n, seed=seed, design=design)
    if kwargs.get("built") is None:
        kwargs["built"] = scenario.build()
    check_samples(samples, "--vary {name}", "a drawn value",
                  vehicle_parameters(*kwargs["built"][:2]))
    result = run_samples(scenario, samples, **kwargs)
    result.seed = seed
    return result
