"""``pipeline batch``: a lab's archive of trials through ``pipeline ik``, locally or on Dask.

The manifest is a CSV with one row per trial: ``subject,sex,height_m,orientations`` and optional
columns named after any other option of ``pipeline ik`` (:func:`option_columns`, from the options'
one definition, :mod:`pipeline.process.options`: ``knee``, ``correction``, ``drift``,
``sensor_to_model`` as ``"-1.5708 0 0"``, ``sensor_map`` as ``"pelvis_imu=ID ..."``, the
subject's measures, ...) and ``config`` (a configuration file the row's cells override); an empty
cell is "not given". Paths are relative to the manifest's folder. Each row runs
:func:`pipeline.commands.ik.run_settings` into ``DIR/<subject>/<recording name>/`` (all or
nothing, as ``pipeline ik``).

* Parallel: on local worker processes (``distributed.LocalCluster``, one thread each; ``workers``
  of them, default one per core, 1 = in this process), or on a running Dask cluster with
  ``scheduler='tcp://HOST:PORT'`` (the workers need this package installed and the files at the
  same paths).
* One failing trial never stops the others: its row says ``failed`` and why.
* A rerun skips rows whose outputs are complete (``skipped``); ``force`` redoes them.
* ``DIR/batch_summary.csv`` lists every row: ``row,subject,orientations,status,message,frames,
  residual_median_deg,flags,seconds,out_dir``, the figures read from each run's
  ``<name>_figures.json``; written when every row has ended (an interrupted batch leaves the
  trials it finished, each complete, and no summary; rerun it to continue).
"""

from __future__ import annotations

import csv
import os
import time
from collections.abc import Mapping
from pathlib import Path

from pipeline.errors import InputError

__all__ = ["REQUIRED_COLUMNS", "SUMMARY_COLUMNS", "option_columns", "read_manifest", "run_batch",
           "run_row"]  # fmt: skip

REQUIRED_COLUMNS = ("subject", "sex", "height_m", "orientations")
SUMMARY_COLUMNS = ("row", "subject", "orientations", "status", "message", "frames",
                   "residual_median_deg", "flags", "seconds", "out_dir")  # fmt: skip
_OUTPUTS = ("_ik.mot", "_landmarks.csv", "_summary.md", "_config.toml", "_figures.json")


def option_columns() -> dict[str, object]:
    """Manifest column -> its option's :class:`~pipeline.option.Spec` (every option of
    ``pipeline ik`` but ``out``, which the batch sets per row), and ``config``."""
    from pipeline.option import Spec
    from pipeline.process.options import all_specs

    cols: dict[str, object] = {s.name: s for s in all_specs() if s.name != "out"}
    cols["config"] = Spec("config", "path", "a configuration file the row's cells override")
    return cols


def read_manifest(path: str | Path) -> list[dict[str, object]]:
    """The manifest's rows as option values (``None`` where a cell is empty), each with its
    ``row`` number (1 = the first data row), ``line`` and ``subject``; refused with the file, the
    column and the line when a column is unknown or a cell malformed."""
    from pipeline.option import from_cell

    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            raw_rows = list(reader)
    except FileNotFoundError:
        raise InputError("no such manifest", file=path) from None
    columns = option_columns()
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise InputError(f"missing column(s) {missing}; expected {list(REQUIRED_COLUMNS)} and "
                         f"any of {sorted(set(columns) - set(REQUIRED_COLUMNS))}", file=path,
                         field="header")  # fmt: skip
    unknown = [c for c in header if c != "subject" and c not in columns]
    if unknown:
        raise InputError(f"unknown column(s) {unknown}; the options are {sorted(columns)}",
                         file=path, field="header")  # fmt: skip
    if not raw_rows:
        raise InputError("no rows after the header", file=path)
    rows = []
    for k, raw in enumerate(raw_rows, start=1):
        line = k + 1
        row: dict[str, object] = {"row": k, "line": line}
        for key, value in raw.items():
            key = (key or "").strip()
            value = (value or "").strip()
            if not key:
                continue
            if key in ("subject", "sex") and not value:
                raise InputError("expected a value", file=path, field=f"{key} (line {line})")
            if key == "subject":
                row[key] = value
            else:
                row[key] = from_cell(columns[key], value, path.parent, path, line) if value \
                    else None
        rows.append(row)
    return rows


def _out_dir(out: Path, row: Mapping[str, object]) -> Path:
    from pipeline.commands.ik import recording_name

    return out / str(row["subject"]) / recording_name(str(row["orientations"]))


def run_row(row: Mapping[str, object], out: str, force: bool = False) -> dict[str, object]:
    """One manifest row through ``pipeline ik`` (what a worker runs); never raises: a failure is
    the row's ``status`` and ``message``."""
    from pipeline.commands.ik import recording_name, run_settings
    from pipeline.process.options import resolve_settings

    folder = _out_dir(Path(out), row)
    name = recording_name(str(row["orientations"]))
    result: dict[str, object] = {c: "" for c in SUMMARY_COLUMNS}
    result.update(row=row["row"], subject=row["subject"], orientations=row["orientations"],
                  out_dir=str(folder))  # fmt: skip
    if not force and all((folder / f"{name}{s}").is_file() for s in _OUTPUTS):
        result.update(status="skipped", message="outputs complete (--force redoes them)",
                      **_figures(folder / f"{name}_figures.json"))  # fmt: skip
        return result
    t0 = time.perf_counter()
    values = {k: v for k, v in row.items() if k not in ("row", "line", "subject", "config")}
    values["out"] = str(folder)
    try:
        run_settings(resolve_settings(row.get("config"), values))
    except (InputError, OSError, ValueError) as exc:
        result.update(status="failed", message=str(exc), seconds=f"{time.perf_counter() - t0:.2f}")
        return result
    except Exception as exc:  # a worker must report, not die: anything else is a failed row too
        result.update(status="failed", message=f"{type(exc).__name__}: {exc}",
                      seconds=f"{time.perf_counter() - t0:.2f}")  # fmt: skip
        return result
    result.update(status="ok", seconds=f"{time.perf_counter() - t0:.2f}",
                  **_figures(folder / f"{name}_figures.json"))  # fmt: skip
    return result


def _figures(path: Path) -> dict[str, str]:
    """Frames, median residual and the number of flags, from a run's ``_figures.json``."""
    import json

    try:
        fig = json.loads(path.read_text(encoding="utf-8"))
        return {"frames": str(fig["frames"]),
                "residual_median_deg": f"{fig['residual_median_deg']:.2f}",
                "flags": str(len(fig["flags"]))}  # fmt: skip
    except (OSError, ValueError, KeyError, TypeError):
        return {"frames": "", "residual_median_deg": "", "flags": ""}


def run_batch(
    manifest: str | Path,
    out_dir: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = True,
) -> str:
    """Run every row of ``manifest`` (module docstring); return the summary lines to print."""
    from tqdm import tqdm

    from pipeline.io.atomic import output_dir, output_set
    from pipeline.io.tables import csv_text

    rows = read_manifest(manifest)
    out = Path(out_dir)
    output_dir(out)
    if workers is not None and workers < 1:
        raise InputError(f"expected at least one worker, got {workers}", field="workers")
    t0 = time.perf_counter()
    bar = tqdm(total=len(rows), desc="trials", unit="trial", disable=not progress)
    results: dict[int, dict] = {}
    where = "in this process"
    if scheduler is None and (workers or os.cpu_count() or 1) == 1:
        for row in rows:
            results[int(row["row"])] = run_row(row, str(out), force)
            bar.update()
    else:
        from distributed import Client, LocalCluster, as_completed

        cluster = None
        if scheduler is None:
            n = workers or min(os.cpu_count() or 1, len(rows))
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None)  # fmt: skip
            where = f"on {n} local worker processes"
        try:
            with Client(scheduler or cluster) as client:
                if scheduler is not None:
                    where = f"on the Dask cluster at {scheduler}"
                futures = [client.submit(run_row, row, str(out.resolve()), force, pure=False)
                           for row in rows]  # fmt: skip
                try:
                    for fut in as_completed(futures):
                        res = fut.result()
                        results[int(res["row"])] = res
                        bar.update()
                except BaseException:
                    client.cancel(futures)
                    raise
        finally:
            if cluster is not None:
                cluster.close()
    bar.close()
    ordered = [results[int(r["row"])] for r in rows]
    with output_set() as outs:
        with outs.open(out / "batch_summary.csv") as fh:
            fh.write(csv_text(ordered, SUMMARY_COLUMNS))
    counts = {s: sum(r["status"] == s for r in ordered) for s in ("ok", "failed", "skipped")}
    lines = [f"{len(rows)} trials {where} in {time.perf_counter() - t0:.1f} s: "
             f"{counts['ok']} ok, {counts['failed']} failed, {counts['skipped']} skipped; "
             f"summary: {out / 'batch_summary.csv'}"]  # fmt: skip
    lines += [f"row {r['row']} ({r['subject']}, {Path(str(r['orientations'])).name}): "
              f"{r['message']}" for r in ordered if r["status"] == "failed"]  # fmt: skip
    return "\n".join(lines)
