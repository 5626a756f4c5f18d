"""Frame by frame with one calibration: the IK of each frame, warm-started from the last.

Each sensor's live orientation (:mod:`pipeline.live.orientation`) is turned about the vertical
by its calibration's turn (:class:`~pipeline.live.calibration.LiveCalibration`) and is the target
of its IMU frame, as offline; :func:`~pipeline.ik.solver.solve_frame` solves the frame from the
last frame's configuration (the same Gauss-Newton steps, limits and tolerance as
:func:`~pipeline.ik.solve_ik`), a frame a sensor misses without that sensor's task. The joint
angles follow as offline (:func:`pipeline.process.solve.observed_angles`, from the segments' frames
of the solved configuration), blank where a sensor
they need is missing (:mod:`pipeline.process.missing`).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pipeline.analysis.joint_angles import angles_of_segments, segment_names
from pipeline.ik.problem import setup_ik
from pipeline.ik.solver import solve_frame
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.live.calibration import LiveCalibration
from pipeline.process.missing import blank_angles, unknown_in
from pipeline.process.solve import observed_angles
from pipeline.rotations import rot_y

__all__ = ["Tracker"]


class Tracker:
    """Frames solved with calibration ``cal`` (module docstring); ``limits``: the joints'."""

    def __init__(self, cal: LiveCalibration, limits: bool = True) -> None:
        self.cal = cal
        self.segments = sorted(cal.sensors.segments)
        self.names = [SEGMENT_SENSOR[seg] for seg in self.segments]
        self.turn = np.stack([rot_y(cal.turns.get(n, 0.0)) for n in self.names])
        frames = {f"{seg}_imu": np.eye(3)[None] for seg in self.segments}
        self.problem = setup_ik(cal.skeleton.model, frames, q0=cal.q, limits=limits)
        self.q = np.array(cal.q, dtype=float)
        sk = cal.skeleton
        self.body = segment_names(sk.legs)  # the segments the angles are taken between
        self._fids = [sk.frame_id(seg) for seg in self.body]
        self._data = sk.model.createData()

    def solve(self, rotations: dict[str, np.ndarray]) -> tuple[np.ndarray, dict, dict]:
        """``(Q (m, nq), angles, poses)`` of a block's frames: ``rotations`` sensor -> (m, 3, 3)
        in the model's y-up world (NaN where missing); ``poses``: segment -> its frames' world
        rotations (m, 3, 3) and positions (m, 3)."""
        m = len(next(iter(rotations.values())))
        nan = np.full((m, 3, 3), np.nan)
        R = np.stack([rotations.get(n, nan) for n in self.names], axis=1)  # (m, k, 3, 3)
        targets = self.turn[None] @ R
        Q = np.empty((m, len(self.q)))
        body = np.empty((len(self.body), m, 3, 3))
        where = np.empty((len(self.body), m, 3))
        p, model, data = self.problem, self.cal.skeleton.model, self._data
        for i in range(m):
            p.RtT[0] = np.swapaxes(targets[i], 1, 2)
            p.finite[0] = np.all(np.isfinite(targets[i]), axis=(1, 2))
            solve_frame(p, 0, self.q)
            Q[i] = self.q
            pin.forwardKinematics(model, data, self.q)
            for j, fid in enumerate(self._fids):
                M = pin.updateFramePlacement(model, data, fid)
                body[j, i], where[j, i] = M.rotation, M.translation
        seg_rot = {seg: targets[:, j] for j, seg in enumerate(self.segments)}
        cal = self.cal
        angles = angles_of_segments(dict(zip(self.body, body, strict=True)), cal.skeleton.legs)
        angles = observed_angles(angles, cal.sensors, seg_rot, cal.placements, cal.H)
        poses = {seg: (body[j], where[j]) for j, seg in enumerate(self.body)}
        return Q, blank_angles(angles, unknown_in(seg_rot)), poses
