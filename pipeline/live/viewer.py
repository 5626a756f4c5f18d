"""The live capture in the rerun viewer, as it comes, never holding the capture up.

:class:`LiveViewer` logs with the rerun SDK what the offline recording shows, under the same
entities (:mod:`pipeline.viz.scene`): each segment's pose (``world/model/<segment>``, its mesh
once per calibration), the landmarks (``world/landmarks/<name>``), the joint angles in degrees
(``plots/<side>_<joint>/<angle>``); and the capture's state (``state``: stand still, calibrated)
and each stride as it completes (``gait/<side>``: its contacts, time, length and speed; the
stride parameters as plots, ``gait/<side>/<parameter>``); the body where the stance foot carried
it (:mod:`pipeline.live.path`), its settled path on the floor (``world/walk/path``). The capture
hands it each block (:meth:`LiveViewer.log`), which only puts the block's last frame in a small
queue, at most :data:`MAX_HZ` a second; a thread logs from the queue. A viewer that is slow or
closed fills the queue and the frames it cannot take are dropped, the capture's own data never:
the capture goes on at its pace whatever the viewer does.
"""

from __future__ import annotations

import queue
import threading
from pathlib import Path

import numpy as np

__all__ = ["MAX_HZ", "LiveViewer"]

#: The viewer is sent at most this many frames a second.
MAX_HZ = 30.0
_QUEUE = 8


class LiveViewer:
    """A rerun viewer of the capture ``name``: ``mode`` ``'spawn'`` (a viewer started here),
    ``'web'`` (the web viewer on 127.0.0.1:``port``) or ``'save'`` (to ``path``, for tests)."""

    def __init__(self, name: str, mode: str, *, path: Path | None = None,
                 port: int = 9090) -> None:
        import rerun as rr

        self.rr = rr
        self.stream = rr.RecordingStream(f"pipeline live {name}")
        if mode == "spawn":
            self.stream.spawn()
        elif mode == "web":
            uri = self.stream.serve_grpc()
            rr.serve_web_viewer(web_port=port, open_browser=False, connect_to=uri)
        elif mode == "save":
            self.stream.save(str(path))
        else:
            raise ValueError(f"unknown viewer mode {mode!r}")
        self.dropped, self._last, self._cal = 0, -np.inf, None
        self._queue: queue.Queue = queue.Queue(maxsize=_QUEUE)
        self._thread = threading.Thread(target=self._loop, name="live-viewer", daemon=True)
        self._thread.start()

    def state(self, text: str) -> None:
        self._put(("state", text))

    def log(self, time: np.ndarray, poses: dict, angles: dict[str, np.ndarray], cal,
            q: np.ndarray | None = None, root: np.ndarray | None = None) -> None:
        """A block: its last frame's segment ``poses`` (segment -> (R (m, 3, 3), p (m, 3))),
        ``angles`` and configuration ``q`` (the landmarks') at ``time`` (m,), the body at
        ``root`` (the pelvis's place in the room, :mod:`pipeline.live.path`; None: at the
        origin), if :data:`MAX_HZ` allows."""
        t = float(time[-1])
        if t - self._last < 1.0 / MAX_HZ:
            return
        self._last = t
        frame = {seg: (R[-1], p[-1]) for seg, (R, p) in poses.items()}
        self._put(("frame", t, frame, {k: float(v[-1]) for k, v in angles.items()},
                   cal if cal is not self._cal else None, cal, q,
                   np.zeros(3) if root is None else np.asarray(root, float)))
        self._cal = cal

    def strides(self, strides: list, path: np.ndarray | None = None) -> None:
        """Strides that just completed (:class:`~pipeline.analysis.strides.Stride`) and the
        pelvis's settled path so far ((n, 3), or None: unchanged)."""
        self._put(("strides", list(strides), path))

    def _put(self, item) -> None:
        try:
            self._queue.put_nowait(item)
        except queue.Full:
            self.dropped += 1

    def _loop(self) -> None:
        while (item := self._queue.get()) is not None:
            try:
                self._show(item)
            except Exception:  # noqa: BLE001 - a viewer gone: the capture goes on without it
                self.dropped += 1

    def _show(self, item) -> None:
        rr, s = self.rr, self.stream
        if item[0] == "state":
            s.log("state", rr.TextLog(item[1]))
            return
        if item[0] == "strides":
            self._strides(item[1])
            if item[2] is not None:
                self._path(item[2])
            return
        _, t, frame, angles, fresh, cal, q, root = item
        s.set_time("time", duration=t)
        if fresh is not None:
            self._meshes(fresh)
        if q is not None:
            self._landmarks(cal, q, root)
        for seg, (R, p) in frame.items():
            if np.all(np.isfinite(R)):
                s.log(f"world/model/{seg}", rr.Transform3D(translation=p + root, mat3x3=R))
        for key, value in angles.items():
            side, joint, angle = key.split("_", 2) if key.count("_") >= 2 else ("", "", key)
            entity = f"plots/{side}_{joint}/{angle}" if side in ("right", "left") else \
                f"plots/{key}"
            if np.isfinite(value):
                s.log(entity, rr.Scalars(np.degrees(value)))

    def _path(self, path: np.ndarray) -> None:
        """The pelvis's settled path on the floor (``world/walk/path``, as offline)."""
        floor = path.copy()
        floor[:, 1] = 0.0
        self.stream.log("world/walk/path", self.rr.LineStrips3D([floor], radii=0.008))

    def _landmarks(self, cal, q: np.ndarray, root: np.ndarray) -> None:
        import pinocchio as pin

        sk = cal.skeleton
        if getattr(self, "_lm_model", None) is not sk.model:
            self._lm_model, self._lm_data = sk.model, sk.model.createData()
            self._lm_ids = {n: sk.frame_id(n) for n in sk.landmark_frames}
        pin.framesForwardKinematics(self._lm_model, self._lm_data, q)
        for name, fid in self._lm_ids.items():
            p = self._lm_data.oMf[fid].translation + root
            self.stream.log(f"world/landmarks/{name}", self.rr.Points3D([p], radii=0.01))

    def _strides(self, strides: list) -> None:
        rr, s = self.rr, self.stream
        for st in strides:
            s.set_time("time", duration=st.start_s)
            s.log(f"gait/{st.side}", rr.TextLog(f"{st.side} initial contact"))
            s.set_time("time", duration=st.end_s)
            length = "" if not np.isfinite(st.stride_length_m) else \
                f", {st.stride_length_m:.2f} m, {st.speed_m_s:.2f} m/s"
            s.log(f"gait/{st.side}", rr.TextLog(
                f"{st.side} stride {st.stride_time_s:.2f} s{length}, stance "
                f"{st.stance_share:.2f}"))
            for name in ("stride_time_s", "stride_length_m", "stance_share"):
                v = getattr(st, name)
                if np.isfinite(v):
                    s.log(f"gait/{st.side}/{name}", rr.Scalars(v))

    def _meshes(self, cal) -> None:
        from pipeline.viz.model import segment_meshes

        for seg, mesh in segment_meshes(cal.skeleton).items():
            self.stream.log(f"world/model/{seg}/mesh", self.rr.Mesh3D(
                vertex_positions=mesh.vertices, triangle_indices=mesh.triangles,
                vertex_normals=mesh.normals), static=True)

    def close(self) -> None:
        """Log what is queued, then stop."""
        self._queue.put(None)
        self._thread.join(timeout=5.0)
        self.stream.flush()
