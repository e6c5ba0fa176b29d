"""jaxrail's on/off environment variables (``JAXRAIL_COMPILATION_CACHE``,
``JAXRAIL_LOOP_KERNELS``): on unless set to 0, off, false or no (any case)."""

import os


def switched_off(variable: str) -> bool:
    """Whether the environment variable ``variable`` turns its feature off."""
    return os.environ.get(variable, "on").lower() in ("0", "off", "false", "no")
