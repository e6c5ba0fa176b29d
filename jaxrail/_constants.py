"""Numbers and names that several modules share, each written once.

This module imports nothing, so the command line's ``--help`` can list
:data:`CONTACT_MODELS` and :data:`INTEGRATORS` without importing the vehicle models.
"""

GRAVITY = 9.81
"""Gravitational acceleration [m/s^2] of every built-in vehicle (a vehicle file's
``gravity`` unless given; the floor accelerations of :mod:`jaxrail.standards.floor`)."""

STEEL_SHEAR_MODULUS = 8.2e10
"""Shear modulus G [Pa] of wheel and rail steel: the default of the Hertz and Polach
functions and of :class:`jaxrail.vehicles.ContactParameters`."""

STEEL_POISSON = 0.28
"""Poisson's ratio nu [-] of wheel and rail steel, beside :data:`STEEL_SHEAR_MODULUS`."""

CONTACT_MODELS = ("online", "table")
"""The contact models (:func:`jaxrail.vehicles.contact_model`): the search at every
evaluation (online) or its table, built once and cached."""

INTEGRATORS = ("tsit5", "imex")
"""The integrators of :class:`jaxrail.simulation.SolverOptions`: diffrax's Tsit5
(explicit) or jaxrail's IMEX (:class:`jaxrail.multibody.imex.IMEX`)."""
