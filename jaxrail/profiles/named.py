"""Profiles by name (built-in) or by file, as the command line and scenarios give them."""

from pathlib import Path

from ._base import WheelProfile
from .files import read_profile
from .s1002 import s1002
from .simplified import simplified_s1002
from .uic60 import uic60

BUILTIN_WHEELS = ("s1002", "s1002-simplified")
BUILTIN_RAILS = ("uic60",)


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
    if path.suffix.lower() in (".prw", ".prr") and path.exists():
        profile = read_profile(path)
        return ("wheel" if isinstance(profile, WheelProfile) else "rail"), profile
    if path.exists():
        raise ValueError(f"{name}: for a text profile file give its kind (wheel or rail)")
    known = ", ".join(BUILTIN_WHEELS + BUILTIN_RAILS)
    raise ValueError(f"unknown profile {name!r}: use one of {known} or a .prw/.prr/.csv file")
