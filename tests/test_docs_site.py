"""The documentation a user reads: the site builds and its API page names and signs every public
object; what the README and the docs name (flags, configuration keys, output columns) exists; no
internal references (issue numbers) reach a user."""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _text() -> str:
    return "\n".join(p.read_text(encoding="utf-8") for p in DOCS)


def _flags() -> set[str]:
    """Every flag of every ``pipeline`` command, and of the scripts (``scripts/*.py``)."""
    from pipeline.cli import build_parser

    parser = build_parser()
    out = {s for a in parser._actions for s in a.option_strings}
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for sub in a.choices.values():
                out |= {s for b in sub._actions for s in b.option_strings}
    for script in (ROOT / "scripts").glob("*.py"):
        out |= set(re.findall(r"add_argument\(\s*\"(--[a-z0-9-]+)\"", script.read_text()))
    return out


def test_no_issue_numbers_reach_a_user():
    found = [m.group(0) for m in re.finditer(r"\b[Ii]ssues? #?\d+|#\d{2,}\b", _text())]
    assert found == []


def test_every_flag_the_docs_name_exists():
    named = set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*[a-z0-9])(?!-)", _text()))
    assert named - _flags() == set()


def test_every_configuration_key_the_docs_name_is_an_option():
    from pipeline.process.options import all_specs

    keys = {s.name for s in all_specs()}
    for block in re.findall(r"```toml\n(.*?)```", _text(), flags=re.S):
        for key in re.findall(r"^\s*([a-z_]+)\s*=", block, flags=re.M):
            assert key in keys or key.endswith("_imu"), key  # [sensors]: our sensor names
    said = re.findall(r"`([a-z_]+) = (?:true|false|[\d.]+|\"\w+\")`", _text())
    assert said and set(said) <= keys


def test_every_output_column_is_defined_in_the_readme():
    from pipeline.analysis.strides import STRIDES_CSV_COLUMNS

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for column in (*STRIDES_CSV_COLUMNS, "cycle_percent"):
        assert f"`{column}`" in readme, column


def test_the_api_page_documents_every_public_name():
    import pipeline

    api = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    documented = {ln.split(":::", 1)[1].strip() for ln in api.splitlines()
                  if ln.startswith(":::")}
    for name in pipeline.__all__:
        if name == "__version__":
            continue
        obj = getattr(pipeline, name)
        assert f"{obj.__module__}.{obj.__name__}" in documented, name


@pytest.mark.slow
def test_the_site_builds_with_a_heading_and_signature_per_object(tmp_path):
    pytest.importorskip("mkdocs")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet",
                           "--site-dir", str(tmp_path)], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "api" / "index.html").read_text(encoding="utf-8")
    api = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    for ident in (ln.split(":::", 1)[1].strip() for ln in api.splitlines() if ln.startswith(":::")):
        assert re.search(rf'<h3 id="{re.escape(ident)}" class="doc doc-heading">', page), ident
    assert page.count('class="doc-signature') >= api.count(":::")
    assert not re.search(r":(func|class|mod|data|meth|attr):`", page)  # roles rendered
    assert (tmp_path / "getting-started" / "index.html").is_file()
