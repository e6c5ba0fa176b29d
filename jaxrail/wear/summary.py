"""The JSON summary of a wear evolution (``jaxrail wear --json``)."""

import numpy as np

from ..results import SIDES


def wheel_labels(n_wheelsets: int) -> list[str]:
    """"wheelset K SIDE", leading wheelset first, left then right."""
    return [f"wheelset {k} {side}" for k in range(1, n_wheelsets + 1) for side in SIDES]


def evolution_summary(evolution: dict, attrs: dict) -> dict:
    """Plain-JSON summary: per wheel (:func:`wheel_labels` order) the wear volume per km
    and the share on the flange over the whole distance (each step weighted by its
    length, the share by the step's volume); per profile (N+1, the new one first) the
    distance, equivalent conicity, flange height, flange thickness and qR [mm]; per
    step the largest height the profile lost [mm]."""
    distance = np.asarray(evolution["distance_km"], dtype=np.float64)
    lengths = np.diff(distance)
    per_km = np.asarray(evolution["wear/volume_per_km"])  # (N, W, 2)
    fraction = np.asarray(evolution["wear/flange_fraction"])
    volume = lengths[:, None, None] * per_km
    total = volume.sum(axis=0)
    flange = np.where(total > 0, (volume * fraction).sum(axis=0) / np.where(total > 0, total, 1),
                      0.0)
    m = evolution["measures"]
    mm = lambda name: [float(1e3 * v) for v in m[name]]  # noqa: E731
    return {
        "route": attrs.get("route"), "wear_model": attrs.get("wear_model"),
        "contact": attrs.get("contact"), "steps": int(len(lengths)),
        "wheels": wheel_labels(per_km.shape[1]),
        "wear_volume_mm3_per_km": [float(v) for v in (total / distance[-1]).ravel()],
        "flange_wear_fraction": [float(v) for v in flange.ravel()],
        "distance_km": [float(d) for d in distance],
        "equivalent_conicity": [None if not np.isfinite(v) else float(v)
                                for v in m["equivalent_conicity"]],
        "flange_height_mm": mm("flange_height"), "flange_thickness_mm": mm("flange_thickness"),
        "qr_mm": mm("qr"),
        "max_height_loss_per_step_mm": [float(1e3 * np.max(v))
                                        for v in evolution["wear/height_loss"]],
    }
