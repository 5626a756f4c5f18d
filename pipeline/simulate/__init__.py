"""Simulation (ground truth for every estimator): a model in, a trial with known truth out. Motions
with exact ``q, v, a`` (:mod:`~pipeline.simulate.motions`), a walk through the room whose feet
stand on the floor (:mod:`~pipeline.simulate.walk`), IMU signals of misplaced noisy sensors
on the model (:func:`simulate_trial`), and a model-free two-segment chain
(:mod:`~pipeline.simulate.chain`).

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "chain_kinematics": "chain",
    "GRAVITY": "model",
    "gravity_vector": "chain",
    "hinge_trial": "joint_trials",
    "imu_signals": "chain",
    "joint_trajectories": "motions",
    "JointTrial": "chain",
    "MAGNETIC_FIELD": "model",
    "motion_name": "motions",
    "MOTIONS": "conventions",
    "point_acceleration": "chain",
    "pose_derivatives": "chain",
    "RAMP_S": "motions",
    "SensorNoise": "model",
    "simulate_trial": "model",
    "SimulatedImu": "model",
    "SimulatedTrial": "model",
    "Sinusoids": "chain",
    "spherical_trial": "joint_trials",
    "walk_plan": "walk",
    "walk_trajectories": "walk",
    "WalkPlan": "walk",
    "standing_start": "motions",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
