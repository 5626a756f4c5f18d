"""OpenSim-free lower-limb IMU-to-skeleton pipeline on Pinocchio.

Implements Wang et al. 2023 (anatomical landmark trajectories from IMC data, IEEE TNSRE 31,
doi:10.1109/TNSRE.2023.3285924) and Hu et al. 2021 (joint-constraint IMU calibration, Sensors 21
7161, doi:10.3390/s21217161). SI units inside: metres, radians, seconds.
"""

__version__ = "0.1.0"
