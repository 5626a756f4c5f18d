"""Reproductions of the papers' results on their published data (``pipeline reproduce``).

Nothing outside this package (and :mod:`pipeline.commands.reproduce`) imports it.
"""

__all__ = ["wang2023"]
