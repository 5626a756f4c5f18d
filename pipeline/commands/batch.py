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
* Nothing escapes ``DIR``: a subject and a recording name are one path component each (no
  ``..``, no separator, not absolute: refused with the row's line), and two rows that would write
  the same folder are refused before anything runs.
* One failing trial never stops the others: its row says ``failed`` and why; the batch then
  exits 1 (``pipeline batch``), 0 when every row is ``ok`` or ``skipped``.
* A rerun skips a row (``skipped``) only when its folder holds the outputs of the same resolved
  configuration (its written ``_config.toml``) and every output the row asks for (``.rrd``,
  ``.osim`` included); ``force`` redoes them.
* ``DIR/batch_summary.csv`` lists every row: ``row,subject,orientations,status,message,frames,
  residual_median_deg,flags,seconds,out_dir``, the figures read from each run's
  ``<name>_figures.json``. It is replaced (atomically) when the batch starts, every row
  ``pending``, and when it ends; SIGTERM or Ctrl-C stops the batch, in one process as on Dask:
  the summary then says which rows finished and which did not run (``not run``), every finished
  trial complete (exit 143 or 130; rerun to continue). A finished batch also writes
  ``DIR/batch_report.html``, the group report (:mod:`pipeline.commands.batch_outputs`).
* ``scheduler``: ``tcp://HOST:PORT`` (or ``tls://``), checked before connecting; a service that
  does not answer as a Dask scheduler within :data:`CONNECT_TIMEOUT_S` is refused.
"""

from __future__ import annotations

import csv
import os
import time
from collections.abc import Mapping
from pathlib import Path

from pipeline.commands.batch_outputs import SUMMARY_COLUMNS, trial_figures, write_summary
from pipeline.errors import InputError, Terminated

__all__ = ["REQUIRED_COLUMNS", "SUMMARY_COLUMNS", "option_columns", "read_manifest", "run_batch",
           "run_row"]

REQUIRED_COLUMNS = ("subject", "sex", "height_m", "orientations")
_OUTPUTS = ("_ik.mot", "_landmarks.csv", "_summary.md", "_config.toml", "_figures.json")
#: Seconds to wait for a Dask scheduler's answer.
CONNECT_TIMEOUT_S = 10


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
    from pipeline.examples import resolve
    from pipeline.option import from_cell

    path = resolve(path)
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            raw_rows = list(reader)
    except FileNotFoundError:
        raise InputError("no such manifest", file=path) from None
    except UnicodeDecodeError as exc:
        raise InputError(f"not UTF-8 text (byte {exc.start}): expected a CSV manifest in UTF-8",
                         file=path) from None
    except csv.Error as exc:
        raise InputError(f"not a CSV manifest: {exc}", file=path) from None
    if any("\0" in h for h in header):
        raise InputError("not a CSV manifest (NUL bytes)", file=path)
    twice = sorted({h for h in header if header.count(h) > 1})
    if twice:
        raise InputError(f"column(s) {twice} given twice", file=path, field="header")
    columns = option_columns()
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if missing:
        raise InputError(f"missing column(s) {missing}; expected {list(REQUIRED_COLUMNS)} and "
                         f"any of {sorted(set(columns) - set(REQUIRED_COLUMNS))}", file=path,
                         field="header")
    unknown = [c for c in header if c != "subject" and c not in columns]
    if unknown:
        raise InputError(f"unknown column(s) {unknown}; the options are {sorted(columns)}",
                         file=path, field="header")
    if not raw_rows:
        raise InputError("no rows after the header", file=path)
    rows = []
    for k, raw in enumerate(raw_rows, start=1):
        line = k + 1
        row: dict[str, object] = {"row": k, "line": line}
        if raw.get(None):
            raise InputError(f"{len(header) + len(raw[None])} cells, the header has "
                             f"{len(header)}", file=path, field=f"line {line}")
        for key, value in raw.items():
            key = (key or "").strip()
            value = (value or "").strip()
            if not key:
                continue
            if key in ("subject", "sex") and not value:
                raise InputError("expected a value", file=path, field=f"{key} (line {line})")
            if key == "subject":
                row[key] = path_component(value, path, f"subject (line {line})")
            else:
                row[key] = from_cell(columns[key], value, path.parent, path, line) if value \
                    else None
        row["orientations"] = _orientations_of(row, path, line)
        from pipeline.commands.ik import recording_name

        path_component(recording_name(str(row["orientations"])), path,
                       f"orientations (line {line})")
        if row.get("name"):
            path_component(str(row["name"]), path, f"name (line {line})")
        rows.append(row)
    return rows


def _orientations_of(row: Mapping[str, object], path: Path, line: int) -> object:
    """The row's recording: its cell, else its configuration file's ``[ik] orientations`` (the
    row's folder is named after it), else refused naming the line."""
    if row.get("orientations") is not None:
        return row["orientations"]
    if row.get("config") is not None:
        from pipeline.io.config import read_config
        from pipeline.process.options import all_specs

        given = read_config(row["config"], all_specs()).get("orientations")
        if given is not None:
            return given
    raise InputError("expected a recording, in the cell or in the row's config ([ik] "
                     "orientations)", file=path, field=f"orientations (line {line})")


def path_component(name: str, file: Path, field: str) -> str:
    """``name`` if it is one path component (a folder name inside ``--out``), else refused."""
    bad = (not name or name in (".", "..") or "/" in name or "\\" in name or "\0" in name
           or Path(name).is_absolute() or (len(name) > 1 and name[1] == ":"))
    if bad:
        raise InputError(f"expected a name for a folder inside --out (no '..', separator or "
                         f"absolute path), got {name!r}", file=file, field=field)
    return name


def _out_dir(out: Path, row: Mapping[str, object]) -> Path:
    from pipeline.commands.ik import recording_name

    return out / str(row["subject"]) / (row.get("name") or recording_name(str(row["orientations"])))


def _check_distinct_folders(rows: list[dict], out: Path, manifest: Path) -> None:
    """Two rows writing one folder are refused before anything runs."""
    seen: dict[Path, int] = {}
    for row in rows:
        folder = _out_dir(out, row)
        if folder in seen:
            raise InputError(f"rows {seen[folder]} and {row['row']} would both write "
                             f"{folder}: give them different subjects or recording names",
                             file=manifest)
        seen[folder] = int(row["row"])


def run_row(row: Mapping[str, object], out: str, force: bool = False) -> dict[str, object]:
    """One manifest row through ``pipeline ik`` (what a worker runs); never raises: a failure is
    the row's ``status`` and ``message``."""
    from pipeline.commands.ik import output_name, run_settings
    from pipeline.process.options import resolve_settings

    folder = _out_dir(Path(out), row)
    name = output_name(row.get("name") or None, str(row["orientations"]))
    result: dict[str, object] = {c: "" for c in SUMMARY_COLUMNS}
    result.update(row=row["row"], subject=row["subject"], orientations=row["orientations"],
                  out_dir=str(folder))
    t0 = time.perf_counter()
    values = {k: v for k, v in row.items() if k not in ("row", "line", "subject", "config")}
    values.update(out=str(folder), overwrite=True)  # a row's folder is the batch's own
    try:
        settings = resolve_settings(row.get("config"), values)
        name = output_name(settings.outputs.name, str(row["orientations"]))
        if not force and _done(folder, name, settings):
            result.update(status="skipped", message="outputs of the same configuration complete "
                          "(--force redoes them)", **trial_figures(folder / f"{name}_figures.json"))
            return result
        run_settings(settings)
    except (InputError, OSError, ValueError) as exc:
        result.update(status="failed", message=str(exc), seconds=f"{time.perf_counter() - t0:.2f}")
        return result
    except Exception as exc:  # a worker must report, not die: anything else is a failed row too
        result.update(status="failed", message=f"{type(exc).__name__}: {exc}",
                      seconds=f"{time.perf_counter() - t0:.2f}")
        return result
    result.update(status="ok", seconds=f"{time.perf_counter() - t0:.2f}",
                  **trial_figures(folder / f"{name}_figures.json"))
    return result


def _done(folder: Path, name: str, settings) -> bool:
    """The folder holds every output ``settings`` ask for, written by the same resolved
    configuration (the ``_config.toml`` without its comment lines)."""
    import importlib.util

    from pipeline.process.options import settings_text

    wanted = list(_OUTPUTS) + [".rrd"] * settings.outputs.rerun + [".osim"] * settings.outputs.osim
    if settings.outputs.report and importlib.util.find_spec("matplotlib") is not None:
        wanted.append("_report.html")
    if not all((folder / f"{name}{s}").is_file() for s in wanted):
        return False
    try:
        written = (folder / f"{name}_config.toml").read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return False

    def body(text: str) -> list[str]:
        return [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]

    return body(written) == body(settings_text(settings))


def run_batch(
    manifest: str | Path,
    out_dir: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = True,
) -> tuple[str, int]:
    """Run every row of ``manifest`` (module docstring); return the summary lines to print and the
    number of failed rows. Interrupted (SIGTERM, Ctrl-C), it writes the summary of the rows done
    and re-raises."""
    from pipeline.io.atomic import output_dir

    rows = read_manifest(manifest)
    out = Path(out_dir)
    if workers is not None and workers < 1:
        raise InputError(f"expected at least one worker, got {workers}", field="workers")
    if scheduler is not None:
        check_scheduler(scheduler)
    _check_distinct_folders(rows, out, Path(manifest))
    output_dir(out)
    t0 = time.perf_counter()
    results: dict[int, dict] = {}
    _write_summary(out, rows, results, "pending")
    try:
        where = _run_rows(rows, out, results, workers, scheduler, force, progress)
    except (KeyboardInterrupt, Terminated):
        _write_summary(out, rows, results, "not run")
        raise
    ordered = _write_summary(out, rows, results, "not run", final=True)
    counts = {s: sum(r["status"] == s for r in ordered) for s in ("ok", "failed", "skipped")}
    lines = [f"{len(rows)} trials {where} in {time.perf_counter() - t0:.1f} s: "
             f"{counts['ok']} ok, {counts['failed']} failed, {counts['skipped']} skipped; "
             f"summary: {out / 'batch_summary.csv'}"]
    lines += [f"row {r['row']} ({r['subject']}, {Path(str(r['orientations'])).name}): "
              f"{r['message']}" for r in ordered if r["status"] == "failed"]
    return "\n".join(lines), counts["failed"]


def _run_rows(rows, out: Path, results: dict, workers, scheduler, force, progress) -> str:
    """Every row's result into ``results`` (row number -> result); where they ran."""
    from tqdm import tqdm

    bar = tqdm(total=len(rows), desc="trials", unit="trial", disable=not progress)
    try:
        if scheduler is None and (workers or os.cpu_count() or 1) == 1:
            for row in rows:
                results[int(row["row"])] = run_row(row, str(out), force)
                bar.update()
            return "in this process"
        return _run_on_dask(rows, out, results, workers, scheduler, force, bar)
    finally:
        bar.close()


def _run_on_dask(rows, out: Path, results: dict, workers, scheduler, force, bar) -> str:
    from pipeline.optional import need

    distributed = need("distributed", "pipeline batch")
    Client, LocalCluster = distributed.Client, distributed.LocalCluster
    as_completed = distributed.as_completed

    cluster = None
    where = f"on the Dask cluster at {scheduler}"
    if scheduler is None:
        n = workers or min(os.cpu_count() or 1, len(rows))
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        where = f"on {n} local worker processes"
    try:
        try:
            client = Client(scheduler or cluster, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError) as exc:
            raise InputError(f"no Dask scheduler answered within {CONNECT_TIMEOUT_S} s ({exc})",
                             field="scheduler") from None
        with client:
            futures = [client.submit(run_row, row, str(out.resolve()), force, pure=False)
                       for row in rows]
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
    return where


def check_scheduler(address: str) -> None:
    """A Dask scheduler's address: ``tcp://HOST:PORT`` or ``tls://HOST:PORT``, port 1-65535."""
    from urllib.parse import urlsplit

    try:
        parts = urlsplit(address)
        port = parts.port
    except ValueError as exc:
        raise InputError(f"expected tcp://HOST:PORT, got {address!r} ({exc})",
                         field="scheduler") from None
    if parts.scheme not in ("tcp", "tls") or not parts.hostname or port is None or port < 1:
        raise InputError(f"expected tcp://HOST:PORT (or tls://), got {address!r}",
                         field="scheduler")
    if parts.scheme == "tcp":
        _probe_dask(parts.hostname, port, address)


def _probe_dask(host: str, port: int, address: str) -> None:
    """A Dask scheduler writes its handshake as soon as a connection opens: a service that
    writes nothing within :data:`CONNECT_TIMEOUT_S` (or refuses the connection) is not one."""
    import socket

    try:
        with socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S) as conn:
            conn.settimeout(CONNECT_TIMEOUT_S)
            if conn.recv(8):
                return
            why = "it closed the connection"
    except TimeoutError:
        why = "it said nothing"
    except OSError as exc:
        why = exc.strerror or str(exc)
    raise InputError(f"no Dask scheduler answered at {address} within {CONNECT_TIMEOUT_S} s "
                     f"({why})", field="scheduler")


def _write_summary(out: Path, rows, results: dict, missing: str, final: bool = False) -> list[dict]:
    """``batch_summary.csv`` replaced atomically: every row, ``missing`` where it has no result;
    ``final``: with the group report (:func:`~pipeline.commands.batch_outputs.write_summary`)."""
    ordered = []
    for r in rows:
        res = results.get(int(r["row"]))
        if res is None:
            res = {c: "" for c in SUMMARY_COLUMNS}
            res.update(row=r["row"], subject=r["subject"], orientations=r["orientations"],
                       status=missing, out_dir=str(_out_dir(out, r)))
        ordered.append(res)
    write_summary(out, ordered, report=final)
    return ordered
