"""pipeline.report.page: the one-page report of a real walk (the shipped x-IMU3 example),
self-contained, rendered by a real headless browser where one is installed; the group report."""

import re
import shutil
import subprocess

import numpy as np
import pytest

from pipeline.report.page import GroupTrial, group_report_html, report_html, symmetry_index

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def page():
    from pipeline.io.formats import read_recording
    from pipeline.model.measures import Measures
    from pipeline.process.run import process_recording

    run = process_recording(read_recording("example:ximu3_lower_body"), Measures("m", 1.8))
    return run, report_html(run, "ximu3_lower_body")


def test_symmetry_index():
    assert symmetry_index(1.1, 0.9) == pytest.approx(20.0)
    assert symmetry_index(1.0, 1.0) == 0.0 and np.isnan(symmetry_index(1.0, np.nan))


def test_the_report_holds_the_curves_the_table_and_the_checks(page):
    run, text = page
    assert text.startswith("<!DOCTYPE html>") and "Gait report: ximu3_lower_body" in text
    assert len(re.findall(r'src="data:image/png;base64,', text)) == 2  # curves and skeleton
    assert not re.search(r'(src|href)="(https?:)?//', text)  # nothing fetched: self-contained
    for heading in ("Joint angles over the gait cycle", "Spatiotemporal parameters",
                    "The skeleton", "Sensor checks"):
        assert f"<h2>{heading}</h2>" in text
    n = len(run.gait.strides)
    assert n > 4 and f"{n} strides found" in text
    assert "<th>symmetry index (%)</th>" in text and "stride length (m)" in text


@pytest.mark.skipif(shutil.which("chromium") is None, reason="no headless chromium here")
def test_a_real_browser_renders_the_figures(page, tmp_path):
    from PIL import Image

    path = tmp_path / "report.html"
    path.write_text(page[1], encoding="utf-8")
    shot = tmp_path / "shot.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu",
                    f"--screenshot={shot}", "--window-size=1100,1400", path.as_uri()],
                   capture_output=True, timeout=120, check=True)
    img = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    green = np.all(np.abs(img - [0x1A, 0x96, 0x41]) < 40, axis=2)
    assert green.sum() > 500  # the right side's curves drawn on the page, not a broken image


def test_the_group_report_lists_every_trial():
    curve = {"n": 2, "mean_deg": [10.0] * 101, "sd_deg": [1.0] * 101}
    fig = {"strides": 8, "stride_time_s": 1.1, "flags": [], "cycles": {
        "right": {"knee_angle": curve}, "left": {"knee_angle": curve}}}
    text = group_report_html([GroupTrial("s1", "walk", fig), GroupTrial("s2", "run", None)])
    assert "<td>s1</td><td>walk</td><td>8</td><td>1.10</td>" in text
    assert "<td>s2</td><td>run</td>" in text and "no figures (failed or not run)" in text
    assert text.count("data:image/png;base64,") == 1
