"""pipeline.live.channels: a stream's channels read from its labels, in any order; a stream
whose labels are not our IMU CSV's columns refused in one line naming it."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.live.channels import layout_of, split


def test_labels_in_any_order_give_each_signal_its_columns():
    labels = ["acc_x", "acc_y", "acc_z", "quat_w", "quat_x", "quat_y", "quat_z", "GYR_X", "gyr_y",
              "gyr_z"]
    layout = layout_of(labels, "tibia_r")
    assert set(layout.columns) == {"gyr", "acc", "quat"}
    values = np.arange(20.0).reshape(2, 10)
    out = split(values, layout)
    np.testing.assert_array_equal(out["gyr"], values[:, 7:10])
    np.testing.assert_array_equal(out["quat"], values[:, 3:7])
    assert layout.labels == [x.lower() for x in labels]


@pytest.mark.parametrize("labels, count, match", [
    (["gyr_x", "gyr_y", "gyr_z"], None, "acc incomplete"),
    (["gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z", "mag_x"], None, "mag incomplete"),
    (["gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z", "temp"], None, "unknown labels"),
    (["gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z"], 9, "has 9 channels but 6 labels"),
    (["gyr_x", "gyr_x", "gyr_z", "acc_x", "acc_y", "acc_z"], None, "repeated"),
])
def test_a_stream_with_other_channels_is_refused_naming_it(labels, count, match):
    with pytest.raises(InputError, match=f"stream 'thigh 7'.*{match}"):
        layout_of(labels, "thigh 7", count)
