"""The tilt-table validation (Sacsayhuaman paper §3.2): ``study`` reads the sweeps of
generated walls (make tilt, tilt-rate, tilt-sensitivity) and writes results/tilt/."""
