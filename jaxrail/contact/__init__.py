"""Wheel-rail contact: search (the paper's section 2), Hertz, normal laws, creep forces."""
