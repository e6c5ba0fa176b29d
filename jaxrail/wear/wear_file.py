"""The wear evolution's HDF5 file: written whole after every completed step, read back to
resume (docs/wear.md lists the layout).

Datasets, each with ``units``, ``description`` and ``axes`` attributes: ``distance``
(N+1,) [km] at each profile; ``profile/y`` (Kw,) [m] the wheel profile's lateral
coordinate; ``profile/height`` (N+1, Kw) [m] the wheel profile at each distance;
``wear/volume_per_km`` (N, W, 2) [mm^3/km]; ``wear/flange_fraction`` (N, W, 2);
``wear/depth_per_km`` (N, W, 2, Kw) [m/km] each wheel's height loss per km;
``wear/height_loss`` (N, Kw) [m] the smoothed loss each step took off the profile;
``rail/y`` (Kr,) [m]; ``rail/depth_per_pass`` (N, 2, Kr) [m]; ``substeps`` (N,) the
route runs of each step; ``measures/<name>``
(N+1,) [m, or 1 for the conicity]; while a step split by ``--max-depth`` is under way,
``pending/<name>`` the records of its sub-steps run so far (:data:`PENDING_FIELDS`),
written after each of them, so that a resumed evolution goes on from the last. Root
attributes: the route, its source text, the options of the run (``key``), the
completed steps and the format version.
"""

import json

import numpy as np

from .._files import write_atomically

FORMAT_VERSION = 1
MEASURES = {"equivalent_conicity": ("1", "equivalent conicity tan(gamma_e) at 3 mm amplitude "
                                          "(EN 15302) on the route's new rails"),
            "flange_height": ("m", "flange height Sh (EN 15313)"),
            "flange_thickness": ("m", "flange thickness Sd (EN 15313)"),
            "qr": ("m", "flange steepness qR (EN 15313)")}
STEP_FIELDS = {
    "wear/volume_per_km": ("mm^3/km", "wear volume per km of each wheel", "step, wheelset, wheel"),
    "wear/flange_fraction": ("1", "share of each wheel's wear on its flange",
                             "step, wheelset, wheel"),
    "wear/depth_per_km": ("m/km", "each wheel's height loss per km on the profile grid",
                          "step, wheelset, wheel, profile/y"),
    "wear/height_loss": ("m", "the smoothed mean height loss taken off the profile in the step",
                         "step, profile/y"),
    "rail/depth_per_pass": ("m", "the rails' height loss per pass of the vehicle (left, right)",
                            "step, rail, rail/y"),
    "substeps": ("1", "the route runs of the step (sub-steps of --max-depth)", "step"),
}

PENDING_FIELDS = {  # the sub-steps run of a step not yet complete (jaxrail.wear.evolution)
    "length_km": ("km", "distance of each sub-step run", "substep"),
    "volume_per_km": ("mm^3/km", "wear volume per km of each wheel", "substep, wheelset, wheel"),
    "flange_per_km": ("mm^3/km", "the part of it on the flange", "substep, wheelset, wheel"),
    "depth_per_km": ("m/km", "each wheel's height loss per km on the profile grid",
                     "substep, wheelset, wheel, profile/y"),
    "rail_depth_per_pass": ("m", "the rails' height loss per pass of the vehicle",
                            "substep, rail, rail/y"),
}


def write_evolution(path, evolution: dict, attrs: dict) -> None:
    """Write ``evolution`` (:func:`jaxrail.wear.evolution.evolve`'s arrays) to ``path``,
    whole or not at all."""
    import h5py

    def dataset(f, name, data, units, description, axes):
        data = np.asarray(data)
        d = f.create_dataset(name, data=data, compression="gzip" if data.size >= 4096 else None)
        d.attrs.update({"units": units, "description": description, "axes": axes})

    def write(temporary):
        with h5py.File(temporary, "w") as f:
            f.attrs.update({"format_version": FORMAT_VERSION, **attrs})
            dataset(f, "distance", evolution["distance_km"], "km",
                    "distance run by each profile", "profile")
            dataset(f, "profile/y", evolution["profile_y"], "m",
                    "wheel profile lateral coordinate from the taping line, toward the field "
                    "side", "profile/y")
            dataset(f, "profile/height", evolution["profile_height"], "m",
                    "wheel profile height (radial, from the taping-line circle)",
                    "profile, profile/y")
            dataset(f, "rail/y", evolution["rail_y"], "m",
                    "rail profile lateral coordinate toward the field side", "rail/y")
            for name, (units, description, axes) in STEP_FIELDS.items():
                dataset(f, name, evolution[name], units, description, axes)
            for name, (units, description) in MEASURES.items():
                dataset(f, f"measures/{name}", evolution["measures"][name], units,
                        description, "profile")
            for name, (units, description, axes) in PENDING_FIELDS.items():
                if evolution.get("pending") is not None:
                    dataset(f, f"pending/{name}", evolution["pending"][name], units,
                            description, axes)

    write_atomically(path, write)


def read_evolution(path) -> tuple[dict, dict]:
    """``(evolution, attrs)`` of a file :func:`write_evolution` wrote; ValueError when it
    is not one."""
    import h5py

    if not h5py.is_hdf5(path):
        raise ValueError(f"{path}: not an HDF5 file; expected a wear evolution file")
    with h5py.File(path, "r") as f:
        if "key" not in f.attrs:
            raise ValueError(f"{path}: not a wear evolution file (no 'key' attribute)")
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        evolution = {"distance_km": f["distance"][()], "profile_y": f["profile/y"][()],
                     "profile_height": f["profile/height"][()], "rail_y": f["rail/y"][()],
                     "measures": {name: f[f"measures/{name}"][()] for name in MEASURES}}
        for name in STEP_FIELDS:
            evolution[name] = f[name][()]
        if "pending" in f:
            evolution["pending"] = {name: f[f"pending/{name}"][()] for name in PENDING_FIELDS}
    return evolution, attrs


def evolution_key(route_text: str, options: dict) -> str:
    """The key an evolution file carries: the route's text and the options that change
    its results (JSON, sorted)."""
    return json.dumps({"route": route_text, **options}, sort_keys=True)
