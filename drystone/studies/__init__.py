"""Studies that reproduce the papers: tilt-table validation, Ogawa et al., the Sacsayhuaman wall."""
