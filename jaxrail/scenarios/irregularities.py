"""A scenario's ``[irregularities]`` table: which irregularity the track carries.

One source per scenario (docs/scenarios.md, docs/track.md)::

    [irregularities]
    spectrum = "german-low"      # a spectrum of jaxrail.track.spectra.SPECTRA
    seed = 7                     # its realisation (int >= 0)
    band = [3.0, 150.0]          # wavelengths [m], shortest first (default 3-150 m)
    step = 0.25                  # sample spacing [m] (default 0.25)
    scale = 1.0                  # factor on every channel (default 1)

    # or a measured file (jaxrail.track.measured; relative to the scenario file):
    # file = "line.csv"
    # or one isolated cosine dip (SI units, as the rest of the scenario):
    # defect = { kind = "lateral", wavelength = 10.0, amplitude = 0.005, position = 60.0 }

A realisation covers the design track (its total length, or ``length`` [m]).
"""

import dataclasses
from pathlib import Path

from ..track.defects import DEFECT_KINDS, cosine_defect
from ..track.measured import read_irregularity
from ..track.spectra import DEFAULT_BAND, check_band, realisation, spectrum
from . import checks

SOURCES = ("spectrum", "file", "defect")
_KEYS = {"spectrum", "seed", "band", "step", "scale", "length", "file", "defect"}
_DEFECT_KEYS = {"kind", "wavelength", "amplitude", "position"}


@dataclasses.dataclass(frozen=True)
class IrregularitySpec:
    """What ``[irregularities]`` asks for (plain values, SI units): ``source`` one of
    :data:`SOURCES` and its settings."""

    source: str
    spectrum: str | None = None
    seed: int = 0
    band: tuple = DEFAULT_BAND
    step: float = 0.25
    scale: float = 1.0
    length: float | None = None
    file: str | None = None
    defect: tuple | None = None  # (kind, wavelength, amplitude, position)

    def build(self, track_length: float):
        """The :class:`~jaxrail.track.Irregularity` (a realisation over ``length``, else
        ``track_length`` [m]; the file; the dip), times ``scale``."""
        if self.source == "spectrum":
            length = self.length if self.length is not None else track_length
            irregularity = realisation(self.spectrum, length, self.step, self.seed, self.band)
        elif self.source == "file":
            irregularity = read_irregularity(self.file)
        else:
            irregularity = cosine_defect(*self.defect)
        return dataclasses.replace(irregularity, scale=self.scale)

    def realise(self, seed):
        """The realisation of this spectrum with ``seed`` (may be traced) over ``length``
        [m] (set), scale 1 (a Monte Carlo sample's, :mod:`jaxrail.montecarlo.batch`)."""
        return realisation(self.spectrum, self.length, self.step, seed, self.band)

    @property
    def covers_outside(self) -> bool:
        """Whether the irregularity holds beyond its samples (a defect is zero outside
        its dip); a spectrum or a file must cover the run."""
        return self.source == "defect"


def _integer(value, name, where):
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{where}: [irregularities] {name} must be an integer >= 0, got {value!r}")
    return value


def parse_irregularities(table, where: str) -> IrregularitySpec | None:
    """The :class:`IrregularitySpec` of an ``[irregularities]`` table (None without one);
    ValueError names the file, the key and what is allowed. A measured ``file`` is read
    and checked here (:func:`jaxrail.track.measured.read_irregularity`), and again when
    the track is built."""
    if table is None:
        return None
    checks.known_keys(table, _KEYS, where, "[irregularities]")
    given = [s for s in SOURCES if s in table]
    if len(given) != 1:
        raise ValueError(f"{where}: [irregularities] needs exactly one of {', '.join(SOURCES)}, "
                         f"got {', '.join(given) or 'none'}")
    source = given[0]
    label = lambda key: f"[irregularities] {key}"  # noqa: E731
    scale = checks.number(table.get("scale", 1.0), "irregularity_scale", where, label("scale"))
    extra = {"spectrum": {"seed", "band", "step", "length"}, "file": set(), "defect": set()}
    for key in table:
        if key not in extra[source] | {source, "scale"}:
            raise ValueError(f"{where}: {label(key)} does not go with {source!r}")
    if source == "spectrum":
        name = checks.text(table, "spectrum", where, "[irregularities]")
        try:
            spectrum(name)
            band = check_band(table.get("band", DEFAULT_BAND))
        except ValueError as error:
            raise ValueError(f"{where}: [irregularities]: {error}") from None
        length = table.get("length")
        return IrregularitySpec(
            source, spectrum=name, seed=_integer(table.get("seed", 0), "seed", where), band=band,
            step=checks.number(table.get("step", 0.25), "irregularity_step", where, label("step")),
            scale=scale,
            length=None if length is None else checks.number(length, "length", where,
                                                             label("length")))
    if source == "file":
        path = Path(checks.text(table, "file", where, "[irregularities]"))
        if not path.is_absolute() and Path(where).exists():
            path = Path(where).parent / path
        if not path.is_file():
            raise ValueError(f"{where}: {label('file')}: no such file {str(path)!r}")
        try:  # read now, so that a bad file stops the scenario before anything runs
            read_irregularity(path)
        except ValueError as error:
            raise ValueError(f"{where}: {label('file')}: {error}") from None
        return IrregularitySpec(source, file=str(path), scale=scale)
    defect = checks.known_keys(table["defect"], _DEFECT_KEYS, where, label("defect"))
    missing = sorted(_DEFECT_KEYS - set(defect))
    if missing:
        raise ValueError(f"{where}: {label('defect')}: missing {', '.join(missing)}")
    kind = checks.text(defect, "kind", where, label("defect"), choices=tuple(DEFECT_KINDS))
    values = tuple(checks.number(defect[key], f"defect_{key}", where, f"{label('defect')} {key}")
                   for key in ("wavelength", "amplitude", "position"))
    return IrregularitySpec(source, defect=(kind, *values), scale=scale)
