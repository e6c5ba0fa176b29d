"""Profiles by name (built-in) or by file, as the command line and scenarios give them."""

from pathlib import Path

from ._base import WheelProfile
from .files import read_profile
from .s1002 import s1002
from .simplified import simplified_s1002
from .uic60 import uic60

BUILTIN_WHEELS = ("s1002", "s1002-simplified")
BUILTIN_RAILS = ("uic60",)
SIMPACK_SUFFIXES = (".prw", ".prr")  # files that tell their kind
TEXT_SUFFIXES = (".csv", ".txt")  # files read as the kind asked for


def named_profile(name: str, inclination="1:40", kind=None):
    """``(kind, profile)``: ``kind`` is "wheel" or "rail".

    ``name`` is a built-in profile (s1002, s1002-simplified, uic60 with
    ``inclination``) or a profile file: .prw/.prr (SIMPACK) tell their kind, text and
    CSV files need ``kind``. ValueError names what is wrong.
    """
    key = str(name).lower()
    if key == "s1002":
        return "wheel", s1002()
    if key == "s1002-simplified":
        return "wheel", simplified_s1002()
    if key == "uic60":
        return "rail", uic60(inclination)
    path = Path(name)
    if kind is not None:
        if kind not in ("wheel", "rail"):
            raise ValueError(f"profile kind must be 'wheel' or 'rail', got {kind!r}")
        return kind, read_profile(path, kind=kind)
    if path.suffix.lower() in SIMPACK_SUFFIXES and path.exists():
        profile = read_profile(path)
        return ("wheel" if isinstance(profile, WheelProfile) else "rail"), profile
    if path.exists():
        raise ValueError(f"{name}: for a text profile file give its kind (wheel or rail)")
    known = ", ".join(BUILTIN_WHEELS + BUILTIN_RAILS)
    raise ValueError(f"unknown profile {name!r}: use one of {known} or a .prw/.prr/.csv file")


def profile_by_name(name: str, inclination="1:40"):
    """``(kind, profile)`` of a name that tells its kind: a built-in profile or a SIMPACK
    file (.prw/.prr). Any other existing file is a ValueError: a text profile file needs
    its kind (``jaxrail profile --kind``, :func:`read_profile`)."""
    path = Path(name)
    if path.exists() and path.suffix.lower() not in SIMPACK_SUFFIXES:
        raise ValueError(f"{name}: for a text profile file use --kind wheel|rail")
    return named_profile(name, inclination)


def profile_of_kind(name: str, kind: str, inclination="1:40"):
    """The ``kind`` ("wheel" or "rail") profile ``name``: a built-in profile, a SIMPACK
    file, or a .csv/.txt profile file read as ``kind``; ValueError when ``name`` is a
    profile of the other kind or none."""
    path = Path(name)
    if path.suffix.lower() in TEXT_SUFFIXES and path.exists():
        return read_profile(path, kind=kind)
    found, profile = profile_by_name(name, inclination)
    if found != kind:
        raise ValueError(f"{name} is a {found} profile, not a {kind} profile")
    return profile
