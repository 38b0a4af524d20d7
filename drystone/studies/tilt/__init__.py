"""The tilt-table validation (Sacsayhuaman paper §3.2): ``study`` runs the ``tilt`` analysis
of generated walls in groups (make tilt, tilt-rate, tilt-sensitivity) and writes results/tilt/."""
