"""OpenSim-free lower-limb IMU-to-skeleton pipeline on Pinocchio.

Implements Wang et al. 2023 (anatomical landmark trajectories from IMC data, IEEE TNSRE 31,
doi:10.1109/TNSRE.2023.3285924) and Hu et al. 2021 (joint-constraint IMU calibration, Sensors 21
7161, doi:10.3390/s21217161). SI units inside: metres, radians, seconds.

The data flow, one package per stage (``docs/architecture.md``): :mod:`pipeline.io` (formats) ->
:mod:`pipeline.model` (scaled subject model) -> :mod:`pipeline.calibration` (AoR, joint
constraints, heading, placement, attitude filter) -> :mod:`pipeline.ik` -> :mod:`pipeline.analysis`
(landmarks, joint angles); :func:`process_recording` runs that chain on a recording;
:mod:`pipeline.commands` are the CLI's commands; :mod:`pipeline.reproduce` the papers.

Public names load their module on first use::

    >>> import pipeline
    >>> pipeline.Measures("f", 1.62).height_m
    1.62
"""

from pipeline._lazy import lazy_exports

__version__ = "0.1.0"

_EXPORTS = {
    "IKOptions": "process",
    "IKRun": "process",
    "InputError": "errors",
    "Measures": "model.measures",
    "Skeleton": "model.skeleton",
    "calibrate": "calibration.calibrate",
    "mot_columns": "process",
    "process_recording": "process",
    "read_orientations_sto": "io.opensim",
    "read_recording": "io.formats",
    "solve_ik": "ik.solver",
}
__all__ = ["__version__", *sorted(_EXPORTS)]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
