"""pyarrow without pandas: the ~0.5 s a recording command need not pay.

pyarrow imports pandas the first time it converts a Python list (rerun's blueprint does), only to
check whether the list is a pandas object. The command-line program owns its process and never
uses pandas there, so it asks (:func:`avoid_pandas_when_recording`) that the first blueprint made
in the process (:func:`pipeline.viz.layout.default_blueprint`, :func:`pandas_shortcut_if_asked`)
first makes pyarrow decide that pandas is absent (:func:`pyarrow_without_pandas`); a command that
writes no recording then pays nothing. The forked child that writes a recording
(:mod:`pipeline.viz.background`) is ours too and does it directly.
"""

from __future__ import annotations

__all__ = ["avoid_pandas_when_recording", "pandas_shortcut_if_asked", "pyarrow_without_pandas"]

_PANDAS_SHORTCUT = False  # set by the command-line program: see avoid_pandas_when_recording


def avoid_pandas_when_recording() -> None:
    """For the command-line program only (it owns its process): the first recording opened in
    this process (its blueprint, :func:`pandas_shortcut_if_asked`) calls
    :func:`pyarrow_without_pandas` first (~0.5 s saved), and a command that writes no recording
    pays nothing."""
    global _PANDAS_SHORTCUT
    _PANDAS_SHORTCUT = True


def pandas_shortcut_if_asked() -> None:
    """:func:`pyarrow_without_pandas` if the program asked for it; before the first blueprint."""
    if _PANDAS_SHORTCUT:
        pyarrow_without_pandas()


def pyarrow_without_pandas() -> bool:
    """Make pyarrow decide, once for this process, that pandas is not there, unless pandas is
    already imported; returns whether it did.

    pyarrow imports pandas (~0.5 s) the first time it converts a Python list (rerun's blueprint
    does), only to check whether the list is a pandas object. No command reads or writes pandas
    objects, so the command-line program (:func:`pipeline.cli.main` run as a program) calls this
    before it records: pandas' import is refused while pyarrow makes that one check, then allowed
    again. Not for library use: afterwards pyarrow's own pandas conversions (``to_pandas``) fail
    in this process.
    """
    import importlib.abc
    import sys

    if "pandas" in sys.modules:
        return False

    class _NoPandas(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name == "pandas" or name.startswith("pandas."):
                raise ImportError("pandas is not used by this command")
            return None

    hook = _NoPandas()
    sys.meta_path.insert(0, hook)
    try:
        import pyarrow as pa

        pa.array([0])  # pyarrow's pandas shim tries the import here and remembers the answer
    finally:
        sys.meta_path.remove(hook)
    return "pandas" not in sys.modules
