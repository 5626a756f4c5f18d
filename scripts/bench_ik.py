"""Benchmark pipeline.ik.solver.solve_ik on a one-leg model: frames/s, single-threaded.

Targets: a smooth 3,000-frame (30 s at 100 Hz) gait-like trial (hip flexion/adduction/rotation,
knee flexion with small off-axis knee rotations, ankle) generated on a free-knee model, with
1 deg RMS orientation noise on every segment target; solved for the femur, tibia and foot frames
with a free (Z-X-Y) and a hinge knee. The model comes from ``pipeline.model.builder`` when it is
importable and works, else from an equivalent model built here with the Pinocchio API.

Usage: ``python scripts/bench_ik.py [--frames 3000] [--repeats 3]``
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

from pipeline.ik.solver import frame_rotations, solve_ik  # noqa: E402
from pipeline.rotations import exp3, normalize  # noqa: E402

# OpenSense on a lower-limb model of the same dimensions, two legs + pelvis (7 sensors), measured
# by scripts/bench_opensense.py on this machine kind (results/bench_opensense.txt); DESIGN.md §8
# quotes ~60 frames/s for the full-body model.
OPENSENSE_FPS = 140.0  # results/bench_opensense.txt (2026-12-02: 125-151 frames/s on this machine)
SEGMENTS = ["right_femur", "right_tibia", "right_foot"]


def _fallback_model(knee: str) -> pin.Model:
    """Fixed pelvis, hip Z-X-Y, knee Z-X-Y ('free') or tilted-axis hinge, ankle Z-X (ISB axes)."""
    m = pin.Model()
    m.addFrame(pin.Frame("pelvis", 0, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    z, x, y = np.array([0.0, 0, 1]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])

    def chain(parent, names_axes, offset, lims):
        for i, (name, axis) in enumerate(names_axes):
            plc = pin.SE3(np.eye(3), np.asarray(offset if i == 0 else (0, 0, 0), dtype=float))
            lo, hi = lims[name]
            parent = m.addJoint(
                parent,
                pin.JointModelRevoluteUnaligned(axis),
                plc,
                f"right_{name}",
                np.array([100.0]),
                np.array([100.0]),
                np.array([lo]),
                np.array([hi]),
            )
        return parent

    lims = {
        "hip_Z": (-1.047, 3.142), "hip_X": (-1.571, 1.047), "hip_Y": (-1.571, 1.047),
        "knee": (0.0, 3.142), "knee_Z": (0.0, 3.142), "knee_X": (-0.524, 0.524),
        "knee_Y": (-0.785, 0.785), "ankle_Z": (-1.571, 0.785), "ankle_X": (-0.524, 0.785),
    }
    hip = chain(0, [("hip_Z", z), ("hip_X", x), ("hip_Y", y)], (0, -0.08, 0.08), lims)
    if knee == "free":
        kn = chain(hip, [("knee_Z", -z), ("knee_X", x), ("knee_Y", y)], (0, -0.42, 0), lims)
    else:
        axis = -normalize(np.array([0.05, 0.1, 1.0]))
        kn = chain(hip, [("knee", axis)], (0, -0.42, 0), lims)
    ank = chain(kn, [("ankle_Z", z), ("ankle_X", x)], (0, -0.40, 0), lims)
    for name, j in (("right_femur", hip), ("right_tibia", kn), ("right_foot", ank)):
        m.addFrame(pin.Frame(name, j, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    return m


def load_models() -> tuple[dict[str, pin.Model], str]:
    try:
        from pipeline.model.builder import build_urdf
        from pipeline.model.geometry import SubjectGeometry

        g = SubjectGeometry.default(1.75)
        models = {}
        with tempfile.TemporaryDirectory() as tmp:
            for knee in ("free", "hinge"):
                path = build_urdf(g, f"{tmp}/leg_{knee}.urdf", knee=knee, legs=("right",))
                models[knee] = pin.buildModelFromUrdf(str(path))
        return models, "pipeline.model.builder (subject-scaled URDF, 1.75 m default geometry)"
    except Exception as exc:  # the builder is developed concurrently: fall back, say why
        src = f"fallback model built with the Pinocchio API ({type(exc).__name__}: {exc})"
        return {k: _fallback_model(k) for k in ("free", "hinge")}, src


def gait_trial(model: pin.Model, n: int, rate: float, seed: int) -> np.ndarray:
    """Smooth gait-like joint angles (by joint name) on the free-knee model, (n, nq)."""
    t = np.arange(n) / rate
    ph = 2 * np.pi * 1.0 * t  # 1 Hz stride
    rng = np.random.default_rng(seed)
    drift = 0.05 * np.sin(2 * np.pi * 0.07 * t)
    angles = {
        "right_hip_Z": 0.35 + 0.45 * np.sin(ph) + drift,  # flexion-extension
        "right_hip_X": 0.08 * np.sin(ph + 0.7),
        "right_hip_Y": 0.10 * np.sin(ph + 1.9),
        "right_knee_Z": 0.6 - 0.55 * np.cos(ph + 0.4) + 0.1 * np.sin(2 * ph),  # 0.05-1.25 rad
        "right_knee_X": 0.05 * np.sin(ph + 2.1),  # off-axis (varus) motion
        "right_knee_Y": 0.12 * np.sin(ph + 0.3),  # tibial rotation
        "right_ankle_Z": 0.2 * np.sin(ph - 1.0),
        "right_ankle_X": 0.08 * np.sin(ph + 2.6),
    }
    q = np.tile(pin.neutral(model), (n, 1))
    for name, a in angles.items():
        q[:, model.joints[model.getJointId(name)].idx_q] = a + 0.002 * rng.standard_normal()
    return q


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=3000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--noise-deg", type=float, default=1.0)
    args = ap.parse_args()

    models, source = load_models()
    print(f"model: {source}")
    rng = np.random.default_rng(0)
    q_true = gait_trial(models["free"], args.frames, 100.0, 1)
    clean = frame_rotations(models["free"], q_true, SEGMENTS)
    sigma = np.deg2rad(args.noise_deg) / np.sqrt(3)  # per-axis, so the angle RMS is noise_deg
    targets = {f: R @ exp3(sigma * rng.standard_normal((args.frames, 3))) for f, R in clean.items()}
    print(
        f"trial: {args.frames} frames, targets {SEGMENTS}, {args.noise_deg:g} deg RMS noise, "
        "pelvis fixed, 1 thread"
    )
    for knee in ("free", "hinge"):
        model = models[knee]
        solve_ik(model, {f: v[:50] for f, v in targets.items()})  # warm-up (imports, caches)
        wall, cpu = np.inf, np.inf
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            res = solve_ik(model, targets)
            cpu = min(cpu, time.process_time() - c0)
            wall = min(wall, time.perf_counter() - t0)
        fps, fps_wall = args.frames / cpu, args.frames / wall
        err = np.rad2deg(np.abs(res.q - q_true)[:, [0, 1, 2]]).mean() if knee == "free" else None
        print(
            f"  {knee:5s} knee (nv={model.nv}): {fps:7.0f} frames/s CPU time "
            f"({1e6 * cpu / args.frames:.0f} us/frame; wall {fps_wall:.0f} frames/s), "
            f"best of {args.repeats}; {fps / OPENSENSE_FPS:.0f}x OpenSense's two-leg rate\n"
            f"        GN iterations/frame {res.iterations.mean():.2f}, "
            f"converged {100 * res.converged.mean():.1f}%, residual RMS median "
            f"{np.rad2deg(np.median(res.residual_rms)):.2f} deg"
            + (f", hip angle error vs truth {err:.2f} deg" if err is not None else "")
        )
    # the same trial on example-robot-data's full human.urdf (36 DoF; right leg targets)
    try:
        from pipeline.model.resources import human_urdf

        human = pin.buildModelFromUrdf(str(human_urdf()))
        names = ("right_upperleg", "right_lowerleg", "right_foot")
        qh = np.tile(pin.neutral(human), (args.frames, 1))
        for jn in ("right_hip_Z", "right_hip_X", "right_hip_Y", "right_knee_Z", "right_ankle_Z"):
            iq = human.joints[human.getJointId(jn)].idx_q
            qh[:, iq] = q_true[:, models["free"].joints[models["free"].getJointId(jn)].idx_q]
        lo, hi = human.lowerPositionLimit, human.upperPositionLimit
        qh = np.clip(qh, lo, hi)
        Rh = frame_rotations(human, qh, list(names))
        th = {f: R @ exp3(sigma * rng.standard_normal((args.frames, 3))) for f, R in Rh.items()}
        cpu = np.inf
        for _ in range(args.repeats):
            c0 = time.process_time()
            res = solve_ik(human, th)
            cpu = min(cpu, time.process_time() - c0)
        print(
            f"  human.urdf (nv={human.nv}, right-leg targets): {args.frames / cpu:7.0f} frames/s "
            f"CPU time; GN iterations/frame {res.iterations.mean():.2f}"
        )
    except Exception as exc:  # optional line: example-robot-data missing or changed
        print(f"  human.urdf skipped ({type(exc).__name__}: {exc})")
    print(
        f"OpenSense reference: ~{OPENSENSE_FPS:.0f} frames/s for two legs + pelvis, measured by "
        "scripts/bench_opensense.py (a one-leg problem here, so the ratio flatters us; the like-"
        "for-like two-leg ratio, measured in one run, is in results/bench_opensense.txt)"
    )


if __name__ == "__main__":
    main()
