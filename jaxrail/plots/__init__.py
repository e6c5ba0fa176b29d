"""Figures (matplotlib figures without pyplot: no backend is selected, :mod:`._figure`)."""
