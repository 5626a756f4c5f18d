"""The sensor vocabulary: our sensor names (OpenSense's), the segment each one sits on, and the
other names recordings use for them. Importable at no cost (no NumPy).

Our names are OpenSense's: ``pelvis_imu``, ``femur_r_imu``, ``tibia_r_imu``, ``calcn_r_imu``
(the foot), the ``_l_`` ones, and ``torso_imu`` (read, but not a segment of this lower-limb
model). Other names a recording may use for them, recognised without a sensor map:

* :data:`SENSOR_ALIASES`: ``foot_r_imu`` / ``foot_l_imu`` for the ``calcn`` sensors;
* :data:`MODEL_FRAME_NAMES`: the model's IMU frame names (``right_femur_imu``, what
  ``pipeline simulate`` names its files);
* :data:`XIMU3_LABELS`: the x-IMU3 body-part labels (``Right Upper Leg``, ``Left Foot``, ...).

Anything else (a lab's labels, an Xsens device id) is named by a sensor map, our name -> a unique
part of the recording's name (:func:`pipeline.io.formats.apply_sensor_map`).
"""

from __future__ import annotations

__all__ = [
    "MODEL_FRAME_NAMES",
    "SEGMENT_SENSOR",
    "SENSOR_ALIASES",
    "SENSOR_NAMES",
    "SENSOR_TO_SEGMENT",
    "XIMU3_LABELS",
    "our_name",
]

#: Our sensor name -> the segment it sits on.
SENSOR_TO_SEGMENT: dict[str, str] = {
    "pelvis_imu": "pelvis",
    "femur_r_imu": "right_femur",
    "tibia_r_imu": "right_tibia",
    "calcn_r_imu": "right_foot",
    "femur_l_imu": "left_femur",
    "tibia_l_imu": "left_tibia",
    "calcn_l_imu": "left_foot",
    "torso_imu": "torso",
}
#: Segment -> our sensor name.
SEGMENT_SENSOR = {seg: name for name, seg in SENSOR_TO_SEGMENT.items()}
SENSOR_ALIASES = {"foot_r_imu": "calcn_r_imu", "foot_l_imu": "calcn_l_imu"}
#: The model's IMU frame names (what ``pipeline simulate`` names its files) -> our sensor names.
MODEL_FRAME_NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items()
                     if seg != "torso"}
#: x-IMU3 example labels (lower case) -> our sensor names.
XIMU3_LABELS = {
    "pelvis": "pelvis_imu",
    "right upper leg": "femur_r_imu", "right lower leg": "tibia_r_imu", "right foot": "calcn_r_imu",
    "left upper leg": "femur_l_imu", "left lower leg": "tibia_l_imu", "left foot": "calcn_l_imu",
}
#: Every name a sensor map may use on its left side (ours and the aliases).
SENSOR_NAMES = tuple(sorted(set(SENSOR_TO_SEGMENT) | set(SENSOR_ALIASES)))


def our_name(name: str) -> str | None:
    """Our sensor name for a recording's ``name`` when it is one we know (ours, an alias, a model
    frame name, an x-IMU3 label, any case), else None."""
    low = name.strip().lower()
    for table in (SENSOR_TO_SEGMENT, SENSOR_ALIASES, MODEL_FRAME_NAMES, XIMU3_LABELS):
        if low in table:
            return low if table is SENSOR_TO_SEGMENT else table[low]
    return None
