"""pipeline.cli_startup: what the program sets up before it parses its arguments."""


def test_program_runs_blas_single_threaded_unless_told(monkeypatch):
    """Run as a program, BLAS pools default to one thread (the program's two processes would
    spin against each other on two cores); a user's setting is kept."""
    from pipeline.cli_startup import BLAS_THREADS, single_threaded_blas

    for var in BLAS_THREADS:
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("OMP_NUM_THREADS", "4")
    single_threaded_blas()
    import os

    assert os.environ["OPENBLAS_NUM_THREADS"] == "1" and os.environ["MKL_NUM_THREADS"] == "1"
    assert os.environ["OMP_NUM_THREADS"] == "4"
