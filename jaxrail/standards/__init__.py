"""The standards' outputs from a run's channels: EN 14363 (running safety and track
loading) and EN 12299 (ride comfort). Plain NumPy on the host: nothing here is traced."""
