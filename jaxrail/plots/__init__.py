"""Figures (matplotlib figures without pyplot: no backend is selected, :mod:`._figure`)."""

from .curve import plot_contact_positions as plot_contact_positions
from .curve import plot_derailment_ratio as plot_derailment_ratio
from .curve import plot_forces as plot_forces
from .curve import plot_lateral_displacements as plot_lateral_displacements
from .geometry import plot_geometry as plot_geometry
from .identification import plot_identification as plot_identification
from .montecarlo import plot_distributions as plot_distributions
from .montecarlo import plot_maps as plot_maps
from .profiles import plot_wheel_on_rail as plot_wheel_on_rail
from .simulation import plot_wheelsets as plot_wheelsets
from .track import plot_irregularity_psd as plot_irregularity_psd
from .vehicle import plot_vehicle as plot_vehicle

__all__ = ["plot_contact_positions", "plot_derailment_ratio", "plot_distributions",
           "plot_forces", "plot_geometry", "plot_identification", "plot_irregularity_psd",
           "plot_lateral_displacements", "plot_maps", "plot_vehicle", "plot_wheel_on_rail",
           "plot_wheelsets"]
