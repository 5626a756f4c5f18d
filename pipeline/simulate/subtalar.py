"""The simulated walk's free ankle: a tibia that turns on its planted foot
(:mod:`pipeline.simulate.walk`, a skeleton built with ``ankle='free'``).

A flat foot whose heading is prescribed, under the subject model's ankle of two axes (flexion,
inversion), keeps the tibia from turning on it: the walk's tibia then turns about its long axis
only as the hip turns the whole leg. The real ankle complex has a third rotation, the subtalar
joint's coupling of the foot's inversion with the tibia's external rotation (and of eversion with
its internal rotation). The simulator's free ankle (``ankle_Y``, the ankle's third JCS angle:
the foot's internal rotation relative to the tibia; the model the IK fits keeps two axes, as the
model of a real ankle has fewer than the ankle) follows the foot's inversion ``i`` in the world,

    c = k i,   k ~ U(ANKLE_TURN_PER_INVERSION), per leg                              (1)

with ``k`` about the coupling coefficient of calcaneal inversion to tibial rotation measured on
bone pins, 0.68 +- 0.15 (8 foot-leg specimens in vitro; PMC5987802).

Measured once by hand (seeds 0, 1; each sensor's 4 Hz angular velocity integrated over each
straight stride, drift removed; the median stride's range about the standing vertical): the
tibia's sensor turns 7-13 deg (2-8 with the two-axis ankle; the real S02 walk 14-25), the femur's
14-21 (10-14; S02 25-27), the tibia's own-motion conditioning 0.28-0.36 (0.27-0.33; S02
0.51-0.54). The knee's and the ankle's centre fits stay hinge-like (weakest directions 3-13 and
4-28 deg from the medio-lateral axis, seeds 0-3; S02's 50-74 and 47-53): what makes the real
ones so is still missing. Per stride the real tibia also swings further in the sagittal plane
(84-86 deg against 53-55; the foot 96-97 and 58).
"""

from __future__ import annotations

import numpy as np

from pipeline.model.skeleton import Skeleton

__all__ = ["ANKLE_TURN_PER_INVERSION", "ankle_turns"]

#: The range (uniform) of (1)'s ``k``: degrees of the tibia's external rotation on the foot per
#: degree of the foot's inversion (the bone-pin mean +- one standard deviation).
ANKLE_TURN_PER_INVERSION = (0.53, 0.83)


def ankle_turns(skeleton: Skeleton, inversion: dict[str, np.ndarray],
                rng: np.random.Generator) -> list[tuple[int, np.ndarray]]:
    """Each leg's ``(q index of its ankle_Y, c per sample)`` by (1), ``inversion``: leg -> the
    foot's inversion in the world (rad, per sample); none for the model's two-axis ankle (and no
    draw from ``rng``)."""
    if skeleton.ankle != "free":
        return []
    return [(skeleton.q_index(f"{x}_ankle_Y"), rng.uniform(*ANKLE_TURN_PER_INVERSION)
             * inversion[x]) for x in skeleton.legs]
