"""pipeline batch: a manifest of trials through pipeline ik, in process, on local Dask workers
and on a running Dask cluster; failures, reruns, refusals and a real SIGTERM."""

import csv
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pipeline.cli import main
from pipeline.commands.batch import read_manifest, run_batch
from pipeline.errors import InputError
from pipeline.io.opensim import write_orientations_sto

sys.path.insert(0, str(Path(__file__).parent))
from test_process import _walk  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def trials(tmp_path_factory):
    folder = tmp_path_factory.mktemp("trials")
    for k in range(3):
        _, _, trial, _ = _walk(folder, n=400, seed=k)
        write_orientations_sto(folder / f"walk{k}.sto", trial)
    return folder


def _manifest(folder, rows, header="subject,sex,height_m,orientations,knee,correction"):
    path = folder / "manifest.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _summary(out):
    with open(out / "batch_summary.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def test_rows_run_fail_alone_and_a_rerun_skips_what_is_complete(trials, tmp_path):
    m = _manifest(trials, ["s1,m,1.75,walk0.sto,free,none", "s2,f,1.62,missing.sto,,",
                           "s1,m,1.75,walk1.sto,hinge,aor"])
    out = tmp_path / "out"
    text, failed = run_batch(m, out, workers=1, progress=False)
    assert "2 ok, 1 failed, 0 skipped" in text and "missing.sto" in text and failed == 1
    rows = _summary(out)
    assert [r["status"] for r in rows] == ["ok", "failed", "ok"]
    assert rows[0]["frames"] == "400" and float(rows[0]["residual_median_deg"]) < 5
    assert "no such file" in rows[1]["message"]
    assert (out / "s1" / "walk0" / "walk0_ik.mot").is_file()
    assert (out / "s1" / "walk1" / "walk1_config.toml").read_text().count('knee = "hinge"') == 1
    group = (out / "batch_report.html").read_text()  # the group report: every row, side by side
    assert group.count("<td>s1</td><td>walk") == 2 and "no figures (failed or not run)" in group
    assert (out / "s1" / "walk0" / "walk0_report.html").is_file()
    again, _ = run_batch(m, out, workers=1, progress=False)
    assert "0 ok, 1 failed, 2 skipped" in again
    assert _summary(out)[0]["frames"] == "400"  # the skipped row's figures, read back
    forced, _ = run_batch(m, out, workers=1, force=True, progress=False)
    assert "2 ok, 1 failed, 0 skipped" in forced


def test_local_dask_workers_and_a_running_cluster(trials, tmp_path):
    from distributed import LocalCluster

    m = _manifest(trials, [f"s{k},m,1.75,walk{k}.sto,free,aor" for k in range(3)])
    local, _ = run_batch(m, tmp_path / "local", workers=2, progress=False)
    assert "on 2 local worker processes" in local and "3 ok" in local
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        text, _ = run_batch(m, tmp_path / "cluster", scheduler=cluster.scheduler_address,
                            progress=False)
    assert f"on the Dask cluster at {cluster.scheduler_address}" in text and "3 ok" in text
    a = (tmp_path / "local" / "s2" / "walk2" / "walk2_ik.mot").read_bytes()
    b = (tmp_path / "cluster" / "s2" / "walk2" / "walk2_ik.mot").read_bytes()
    assert a == b  # the same trial gives the same result wherever it runs


@pytest.mark.parametrize(
    "header, row, match",
    [
        ("subject,sex,height_m", "s,m,1.8", "missing column"),
        ("subject,sex,height_m,orientations,kne", "s,m,1.8,a.sto,free", "unknown column"),
        ("subject,sex,height_m,orientations,sensor_to_model", "s,m,1.8,a.sto,-90 x 0",
         "numbers separated by spaces"),
        ("subject,sex,height_m,orientations,osim", "s,m,1.8,a.sto,maybe", "true or false"),
        ("subject,sex,height_m,orientations", ",m,1.8,a.sto", "expected a value"),
    ],
)
def test_a_bad_manifest_is_refused_naming_file_column_and_line(tmp_path, header, row, match):
    m = _manifest(tmp_path, [row], header=header)
    with pytest.raises(InputError, match=match) as exc:
        read_manifest(m)
    assert exc.value.file == str(m)


def test_cli_batch_and_its_sigterm_stops_every_worker(trials, tmp_path):
    import psutil

    m = _manifest(trials, [f"s{k},m,1.75,walk{k % 3}.sto,free,aor" for k in range(12)])
    out = tmp_path / "out"
    assert main(["batch", str(m), "--out", str(tmp_path / "small"), "--workers", "1"]) == 0
    bad = _manifest(tmp_path, ["s1,m,1.75,missing.sto,free,none"])
    assert main(["batch", str(bad), "--out", str(tmp_path / "bad"), "--workers", "1"]) == 1
    proc = subprocess.Popen([sys.executable, "-m", "pipeline", "batch", str(m), "--out",
                             str(out), "--workers", "2"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    children = []
    deadline = time.time() + 60
    while time.time() < deadline and not (out.exists() and any(out.rglob("*_ik.mot"))):
        children = psutil.Process(proc.pid).children(recursive=True) or children
        time.sleep(0.2)
    children = psutil.Process(proc.pid).children(recursive=True) or children
    assert children, "the workers never started"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    time.sleep(1.0)
    alive = [c for c in children if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]
    assert not alive, alive
    statuses = {r["status"] for r in _summary(out)}  # the rows done, the others "not run"
    assert "not run" in statuses and statuses <= {"ok", "not run"}, statuses
    # every trial folder that exists is complete: outputs are all-or-nothing
    for folder in (p for p in out.glob("*/*") if p.is_dir()):
        names = {p.name for p in folder.iterdir()}
        stem = folder.name
        assert {f"{stem}_ik.mot", f"{stem}_summary.md", f"{stem}_config.toml"} <= names, names


def test_sigterm_stops_a_one_process_batch_too(trials, tmp_path):
    """In one process the run of a row must not take SIGTERM for the row's failure."""
    m = _manifest(trials, [f"s{k},m,1.75,walk{k % 3}.sto,free,none" for k in range(30)])
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "pipeline", "batch", str(m), "--out",
                             str(out), "--workers", "1"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and not (out.exists() and any(out.rglob("*_ik.mot"))):
        time.sleep(0.1)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "batch_summary.csv lists them" in err
    rows = _summary(out)
    assert len(rows) == 30 and rows[-1]["status"] == "not run"
    assert not any(r["status"] == "failed" for r in rows)


@pytest.mark.parametrize("subject", ["../escaped", "/tmp/x", "..", "a/b", "."])
def test_a_subject_that_is_not_one_folder_name_is_refused(tmp_path, subject):
    m = _manifest(tmp_path, [f"{subject},m,1.8,a.sto"], header="subject,sex,height_m,orientations")
    with pytest.raises(InputError, match=r"subject \(line 2\).*inside --out"):
        read_manifest(m)


def test_two_rows_writing_one_folder_are_refused_before_anything_runs(trials, tmp_path):
    m = _manifest(trials, ["s1,m,1.75,walk0.sto,free,none", "s1,m,1.75,walk0.sto,hinge,none"])
    with pytest.raises(InputError, match="rows 1 and 2 would both write"):
        run_batch(m, tmp_path / "out", workers=1, progress=False)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("content, match", [
    ("subject,sex,height_m,orientations,knee,knee\ns,m,1.8,a.sto,free,hinge\n", "given twice"),
    ("subject,sex,height_m,orientations\ns,m,1.8,a.sto,extra\n", "5 cells, the header has 4"),
    ("subject,sex,height_m,orientations\nJos\xe9,m,1.8,a.sto\n".encode("latin-1"), "not UTF-8"),
    ("subject,sex,height_m,orientations\n".encode("utf-16"), "not UTF-8"),
])
def test_malformed_manifests_are_one_line_errors(tmp_path, content, match):
    m = tmp_path / "m.csv"
    m.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(InputError, match=match):
        read_manifest(m)


def test_a_row_is_skipped_only_when_its_configuration_and_outputs_are_the_same(trials, tmp_path):
    out = tmp_path / "out"
    m = _manifest(trials, ["s1,m,1.75,walk0.sto,free,none"])
    run_batch(m, out, workers=1, progress=False)
    text, _ = run_batch(m, out, workers=1, progress=False)
    assert "1 skipped" in text
    changed = _manifest(trials, ["s1,m,1.80,walk0.sto,free,none"])  # the height changed
    text, _ = run_batch(changed, out, workers=1, progress=False)
    assert "1 ok" in text
    more = _manifest(trials, ["s1,m,1.80,walk0.sto,free,none,true"],
                     header="subject,sex,height_m,orientations,knee,correction,osim")
    text, _ = run_batch(more, out, workers=1, progress=False)  # .osim asked now: not complete
    assert "1 ok" in text and (out / "s1" / "walk0" / "walk0.osim").is_file()


@pytest.mark.parametrize("address", ["not-a-url", "http://localhost:8786", "tcp://host:99999",
                                     "tcp://:8786", "tcp://host"])
def test_a_scheduler_address_is_checked(tmp_path, address):
    m = _manifest(tmp_path, ["s,m,1.8,a.sto"], header="subject,sex,height_m,orientations")
    with pytest.raises(InputError, match="field scheduler"):
        run_batch(m, tmp_path / "out", scheduler=address, progress=False)


def test_a_service_that_is_not_a_dask_scheduler_is_refused_within_the_timeout(trials, tmp_path,
                                                                               monkeypatch):
    import socket
    import threading

    from pipeline.commands import batch

    monkeypatch.setattr(batch, "CONNECT_TIMEOUT_S", 2)
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    m = _manifest(trials, ["s1,m,1.75,walk0.sto,free,none"])
    t0 = time.time()
    try:
        with pytest.raises(InputError, match=r"within 2 s \(it said nothing\)"):
            run_batch(m, tmp_path / "out", scheduler=f"tcp://127.0.0.1:{server.getsockname()[1]}",
                      progress=False)
    finally:
        server.close()
    assert time.time() - t0 < 20


def test_a_row_whose_recording_comes_from_its_config(trials, tmp_path):
    """An empty orientations cell with a config that gives it (before: written to s1/None/ and
    never skipped): the folder is named after the config's recording, a rerun skips it; a row
    with neither is refused naming its line."""
    cfg = tmp_path / "s1.toml"
    cfg.write_text(f'[ik]\norientations = "{trials / "walk0.sto"}"\nknee = "free"\n')
    m = _manifest(tmp_path, [f"s1,m,1.75,,{cfg}"], header="subject,sex,height_m,orientations,"
                                                          "config")
    out = tmp_path / "out"
    text, failed = run_batch(m, out, workers=1, progress=False)
    assert failed == 0 and (out / "s1" / "walk0" / "walk0_ik.mot").is_file()
    assert not (out / "s1" / "None").exists()
    assert "1 skipped" in run_batch(m, out, workers=1, progress=False)[0]
    bare = _manifest(tmp_path, ["s1,m,1.75,,"], header="subject,sex,height_m,orientations,config")
    with pytest.raises(InputError, match=r"field orientations \(line 2\): expected a recording"):
        read_manifest(bare)
