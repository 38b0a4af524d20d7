"""The Sacsayhuaman wall-section study (paper §4-5): analysis, figures, study driver."""
