"""A study's finished chunks on disk, so that an interrupted study resumes.

After each chunk the rows of every finished sample are written to one JSON file, whole
or not at all (:func:`jaxrail._files.write_text`), with a key of the study: a hash of
the scenario (every value it was read into), the samples drawn (so the seed, the
design and the variations), the duration, the contact mode and the chunk size. A
second run of the same study skips the chunks it finds finished; a different study
refuses the file unless asked to overwrite it.

On several processes (``jax.distributed``) only process 0 keeps the file;
:func:`shared_rows` hands its finished rows to every process, so that all skip the same
chunks (each chunk's gather is a collective that every process must join) and all
hold the whole table. A study whose table goes to OUT keeps its chunks in
OUT.chunks.json (:func:`checkpoint_path`) and removes it once the table is written.
"""

import dataclasses
import hashlib
import json
import math
from pathlib import Path

import numpy as np

from .._files import write_text
from . import coordination

FORMAT = "jaxrail montecarlo checkpoint 2"  # 2: the EN 14363 and EN 12299 columns
PIECE_CHARACTERS = 1 << 20  # a key-value store's value stays well under gRPC's 4 MB
SHARE_TIMEOUT_MS = 3600 * 1000


def checkpoint_path(table_path) -> Path:
    """Where a study that writes its table to ``table_path`` keeps its finished chunks
    while it runs: ``<table_path>.chunks.json`` beside it."""
    return Path(f"{table_path}.chunks.json")


def resumes(path, overwrite: bool = False) -> bool:
    """Whether a study with the checkpoint ``path`` (None: none) starts from the chunks
    it holds: it exists and ``overwrite`` is not set (:meth:`Checkpoint.open` refuses
    it if it holds another study)."""
    return path is not None and Path(path).exists() and not overwrite


def study_key(scenario, samples: dict, duration, contact, chunk) -> str:
    """Hex key of a study (module docstring)."""
    described = {
        "scenario": dataclasses.asdict(scenario),
        "samples": {k: np.asarray(v, np.float64).tolist() for k, v in sorted(samples.items())},
        "duration": float(duration), "contact": contact, "chunk": chunk,
    }
    text = json.dumps(described, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _plain(value):
    """A row's value as JSON takes it (NumPy scalars as Python numbers)."""
    if isinstance(value, (np.floating, float)):
        return float(value)
    if isinstance(value, (np.integer, int)) and not isinstance(value, bool):
        return int(value)
    return value


def rows_to_json(rows: dict) -> dict:
    """``{sample index: row}`` as JSON takes it (string keys, Python numbers)."""
    return {str(k): {key: _plain(v) for key, v in row.items()} for k, row in sorted(rows.items())}


def rows_from_json(data: dict) -> dict:
    """The rows of :func:`rows_to_json` back (a NaN that JSON wrote as null is NaN)."""
    return {int(k): {key: (math.nan if v is None else v) for key, v in row.items()}
            for k, row in data.items()}


def shared_rows(rows: dict, client=None, process=None) -> dict:
    """Process 0's ``rows`` {sample index: row} on every process: with one process
    ``rows`` itself, with several passed through ``client`` (default JAX's distributed
    client: its coordination service's key-value store,
    :mod:`jaxrail.montecarlo.coordination`, in pieces of at most
    ``PIECE_CHARACTERS``); ``process``: this process's index (default JAX's)."""
    import jax

    if client is None and jax.process_count() == 1:
        return rows
    client = coordination.client() if client is None else client
    key = coordination.next_key("montecarlo/rows")
    if (jax.process_index() if process is None else process) == 0:
        text = json.dumps(rows_to_json(rows), allow_nan=True)
        pieces = [text[i:i + PIECE_CHARACTERS] for i in range(0, len(text), PIECE_CHARACTERS)]
        for i, piece in enumerate(pieces):
            client.key_value_set(f"{key}/{i}", piece)
        client.key_value_set(f"{key}/pieces", str(len(pieces)))
        return rows
    count = int(client.blocking_key_value_get(f"{key}/pieces", SHARE_TIMEOUT_MS))
    text = "".join(client.blocking_key_value_get(f"{key}/{i}", SHARE_TIMEOUT_MS)
                   for i in range(count))
    return rows_from_json(json.loads(text))


@dataclasses.dataclass
class Checkpoint:
    """The finished rows ``{sample index: row}`` of the study ``study`` kept at ``path``."""

    path: Path
    study: str
    samples: int
    rows: dict

    @classmethod
    def open(cls, path, study: str, samples: int, overwrite: bool = False) -> "Checkpoint":
        """The checkpoint at ``path``: its rows when it holds this study, empty when there is
        none (or ``overwrite``); ValueError when it holds another study or is not one."""
        path = Path(path)
        if not path.exists() or overwrite:
            return cls(path, study, samples, {})
        try:
            saved = json.loads(path.read_text(encoding="utf-8"))
            if saved.get("format") != FORMAT:
                raise ValueError("not a checkpoint")
        except (ValueError, UnicodeDecodeError) as error:
            raise ValueError(f"{path}: not a jaxrail Monte Carlo checkpoint ({error}); remove it "
                             "or pass --overwrite") from None
        if saved["study"] != study or saved["samples"] != samples:
            raise ValueError(f"{path}: holds the finished chunks of another study (the "
                             "scenario, samples, seed, variations, duration, contact mode or "
                             "chunk differ); remove it or pass --overwrite to start again")
        return cls(path, study, samples, rows_from_json(saved["rows"]))

    def add(self, rows: dict) -> None:
        """Keep ``rows`` {sample index: row} and write the file whole."""
        self.rows.update(rows)
        data = {"format": FORMAT, "study": self.study, "samples": self.samples,
                "rows": rows_to_json(self.rows)}
        write_text(self.path, json.dumps(data, allow_nan=True))
