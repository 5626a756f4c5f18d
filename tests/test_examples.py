"""pipeline.examples: the shipped recordings are found by name and read by every command."""

import pytest

from pipeline.errors import InputError
from pipeline.examples import EXAMPLES, path, resolve


def test_every_example_is_there_with_its_licence():
    for name in EXAMPLES:
        assert path(name).exists(), name
    assert "MIT License" in (path("ximu3_lower_body") / "LICENSE.md").read_text()
    readme = (path("ximu3_lower_body").parent / "README.md").read_text()
    assert "Apache License 2.0" in readme and "MIT licence" in readme


def test_example_names_resolve_and_unknown_ones_are_refused(tmp_path):
    assert resolve("example:ximu3_lower_body") == path("ximu3_lower_body")
    assert resolve(tmp_path / "walk.sto") == tmp_path / "walk.sto"
    with pytest.raises(InputError, match="no example 'nope'"):
        resolve("example:nope")


def test_pipeline_ik_on_an_example_names_its_outputs_after_it(tmp_path):
    """From a clone or a wheel, no other data: the outputs are named after the example, and the
    written configuration keeps its name (it reproduces the run anywhere)."""
    import tomllib

    from pipeline.cli import main

    args = ["ik", "--orientations", "example:opensense_imu_ik_test", "--sex", "m",
            "--height-m", "1.8", "--no-rerun", "--out", str(tmp_path)]
    assert main(args) == 0
    config = tomllib.loads((tmp_path / "opensense_imu_ik_test_config.toml").read_text())
    assert config["ik"]["orientations"] == "example:opensense_imu_ik_test"
