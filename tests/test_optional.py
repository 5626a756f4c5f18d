"""pipeline.optional: a missing extra is named in one line."""

import pytest

from pipeline.errors import InputError
from pipeline.optional import EXTRAS, need


def test_an_installed_module_is_returned():
    assert need("json", "anything").dumps([1]) == "[1]"


def test_a_missing_module_names_its_extra(monkeypatch):
    import builtins

    real = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.split(".")[0] == "distributed":
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_dask)
    monkeypatch.delitem(__import__("sys").modules, "distributed", raising=False)
    with pytest.raises(InputError, match=r"pipeline batch needs distributed, which the 'batch' "
                       r"extra installs: pip install 'imu-skeleton-pipeline\[batch\]'"):
        need("distributed", "pipeline batch")
    assert EXTRAS["matio"] == EXTRAS["ezc3d"] == "reproduce"


def test_the_core_install_lists_no_extra_dependency():
    """pyproject's core dependencies: what pipeline ik and demo need, none of the extras'."""
    from pathlib import Path

    import tomllib

    doc = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    core = " ".join(doc["project"]["dependencies"])
    assert not any(m in core for m in ("dask", "mat-io", "ezc3d", "matplotlib"))
    extras = doc["project"]["optional-dependencies"]
    assert {"batch", "reproduce", "all", "test"} <= set(extras)
