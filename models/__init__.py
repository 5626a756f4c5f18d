"""Shipped data (installed as ``pipeline.models``): Wang 2023 Table I coefficients and the
population knee AoR. Read through :func:`pipeline.model.resources.models_file`."""
