"""The package layout: import direction, lazy loading, module size, and a non-editable install.

These guard the architecture of ``docs/architecture.md``: stages import one way (no circles, no
private names across modules), ``pipeline ik`` loads neither the reproduction nor SciPy's stats
nor CasADi, and a wheel carries the shipped tables.
"""

from __future__ import annotations

import ast
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "pipeline"
STO = ROOT.parent / "shared" / "data" / "opensim" / "quaternions_4_ik.sto"


def _modules() -> dict[str, Path]:
    out = {}
    for f in PACKAGE.rglob("*.py"):
        name = ".".join(f.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        out[name] = f
    return out


def _imports(path: Path) -> list[tuple[str, list[str], bool]]:
    """(module, names, at runtime) of every ``from pipeline... import`` in a file; imports under
    ``if TYPE_CHECKING:`` do not run."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    typing_only = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING":
            typing_only |= {id(n) for n in ast.walk(node)}
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("pipeline"):
            out.append((node.module, [a.name for a in node.names], id(node) not in typing_only))
    return out


def test_no_import_cycles_and_no_private_names_across_modules():
    mods = _modules()
    edges: dict[str, set[str]] = {m: set() for m in mods}
    private = []
    for m, f in mods.items():
        for target, names, runtime in _imports(f):
            for n in names:
                dunder = n.startswith("__") and n.endswith("__")  # e.g. __version__
                if n.startswith("_") and not dunder and target != "pipeline._lazy":
                    private.append(f"{m} imports {target}.{n}")
                if runtime:
                    edges[m].add(f"{target}.{n}" if f"{target}.{n}" in mods else target)
    assert not private
    state: dict[str, int] = {}
    cycles = []

    def visit(m: str, stack: list[str]) -> None:
        state[m] = 1
        for t in edges.get(m, ()):
            if state.get(t) == 1:
                cycles.append(stack[stack.index(t) :] + [t])
            elif t in mods and t not in state:
                visit(t, [*stack, t])
        state[m] = 2

    for m in sorted(mods):
        if m not in state:
            visit(m, [m])
    assert not cycles, cycles


def test_nothing_outside_reproduce_imports_it():
    offenders = [
        m
        for m, f in _modules().items()
        if not m.startswith(("pipeline.reproduce", "pipeline.commands.reproduce"))
        and any(t.startswith("pipeline.reproduce") for t, _, _ in _imports(f))
    ]
    assert not offenders


def test_modules_stay_small():
    sizes = {m: len(f.read_text(encoding="utf-8").splitlines()) for m, f in _modules().items()}
    assert {m: n for m, n in sizes.items() if n > 400} == {}


def test_packages_state_their_stage_and_export_their_public_names():
    import importlib

    packages = ("io", "model", "calibration", "ik", "analysis", "simulate", "viz", "commands",
                "process", "live", "report")
    for pkg in packages:
        module = importlib.import_module(f"pipeline.{pkg}")
        assert module.__doc__ and len(module.__doc__) > 80, pkg
        assert module.__all__, pkg
        for name in module.__all__:
            assert getattr(module, name) is not None, (pkg, name)


def _run(code: str, cwd: Path = ROOT, env: dict | None = None) -> str:
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


@pytest.mark.dataset
@pytest.mark.skipif(not STO.is_file(), reason="needs ../shared/data/opensim")
def test_ik_command_loads_only_what_it_uses(tmp_path):
    out = _run(f"""
        import sys
        from pipeline.cli import main
        assert main(["ik", "--orientations", {str(STO)!r}, "--sex", "m", "--height-m", "1.8",
                     "--out", {str(tmp_path)!r}]) == 0
        heavy = [m for m in ("pipeline.reproduce", "scipy.stats", "casadi") if m in sys.modules]
        print("LOADED", heavy)
    """)
    assert "LOADED []" in out


def test_help_loads_no_domain_code():
    out = _run("""
        import sys
        from pipeline.cli import build_parser
        build_parser()
        heavy = ("numpy", "pinocchio", "pipeline.model.builder")
        print(sorted(m for m in sys.modules if m.startswith(heavy)))
    """)
    assert out.strip() == "[]"


@pytest.mark.slow
def test_wheel_installs_and_scales_a_model(tmp_path):
    """A non-editable install: the wheel alone (shipped tables inside) scales a model."""
    import shutil

    src = tmp_path / "src"  # build from a copy: setuptools leaves build/ in the source tree
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("pipeline", "models"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(wheels),
                    str(src)], check=True, capture_output=True, timeout=600)
    (wheel,) = wheels.glob("imu_skeleton_pipeline-*.whl")
    target = tmp_path / "site"
    install = [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(target)]
    subprocess.run([*install, str(wheel)], check=True, capture_output=True, timeout=600)
    # dependencies come from this environment; the package itself from the wheel's files
    out = _run(
        f"""
        import sys
        sys.path.insert(0, {str(target)!r})
        import pipeline
        assert pipeline.__file__.startswith({str(target)!r}), pipeline.__file__
        from pipeline.cli import main
        assert main(["scale", "--sex", "f", "--height-m", "1.62", "--out", "s.urdf"]) == 0
        from pipeline.io.formats import read_recording
        rec = read_recording("example:ximu3_lower_body")  # the examples ship in the wheel
        assert len(rec.sensors) == 7 and read_recording("example:opensense_imu_ik_test").sensors
        from pipeline.model.resources import models_file
        print(models_file("wang2023_knee_aor.csv"))
        """,
        cwd=tmp_path,
    )
    assert out.strip().splitlines()[-1].startswith(str(target))
    assert "<robot" in (tmp_path / "s.urdf").read_text()


def test_no_inert_formatter_markers():
    """No formatter runs on this tree (its layout is kept by hand within 100 columns and `ruff
    check`): a formatter's skip marker would only say it does."""
    marked = [str(p.relative_to(ROOT)) for folder in ("pipeline", "tests", "scripts")
              for p in (ROOT / folder).rglob("*.py") if "# fmt" + ": skip" in p.read_text()]
    assert marked == []
