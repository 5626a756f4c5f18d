"""Reproductions of the papers' results on their published data (``pipeline reproduce``)."""

from pipeline.reproduce.wang2023.run import reproduce_wang2023

__all__ = ["reproduce_wang2023"]
