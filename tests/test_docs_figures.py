"""The figures the README and docs/results.md quote are the ones the benchmarks last wrote to
results/: each quoted figure is found beside the value its results file holds (issue 25: a
documented figure and its results file never disagree)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NUM = r"(-?[\d.]+)"

_RESULTS = "docs/results.md"


def _realism(quantity: str, column: int) -> tuple[str, str]:
    """bench_sim_realism's ``quantity`` row, its ``column``-th value (1: S02, 2: the x-IMU3 walk,
    3: the ideal simulated walk, 4: the simulated walk)."""
    return ("results/bench_sim_realism.txt",
            rf"\| {re.escape(quantity)} \|" + r" [\d.]+ \|" * (column - 1) + rf" {NUM} \|")


#: (document, its regex with the figure as group 1, results file, its regex for the same figure)
FIGURES = [
    ("docs/results.md", rf"vendor orientations {NUM}°", "results/bench_real_gait.txt",
     rf"\| vendor \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"VQF 9-D {NUM}°", "results/bench_real_gait.txt",
     rf"\| vqf9 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"magnetometers\) {NUM}°", "results/bench_real_gait.txt",
     rf"\| vqf6 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"the PI filter 6-D {NUM}°", "results/bench_real_gait.txt",
     rf"\| pi6 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("README.md", rf"median RMSE is\n{NUM}° from the vendor", "results/bench_real_gait.txt",
     rf"\| vendor \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("README.md", rf"differ from each other by {NUM}°", "results/bench_real_gait.txt",
     rf"\| optical floor \| {NUM} \|"),
    ("README.md", rf"removed ours is {NUM}-[\d.]+°", "results/bench_real_gait.txt",
     rf"\| vqf9 \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("README.md", rf"removed ours is [\d.]+-{NUM}°", "results/bench_real_gait.txt",
     rf"\| pi6 \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("README.md", rf"and {NUM}° from raw signals", "results/bench_real_gait.txt",
     rf"\| vqf9 \| defaults \|.*\*\*{NUM}\*\* \|"),
    *(("docs/results.md", rf"puts the knees {doc} mm and the ankles", "results/bench_real_gait.txt",
       rf"\| defaults \| {ref} \| {NUM} \|") for doc, ref in (
        (rf"{NUM}-[\d.]+", "markers"), (rf"[\d.]+-{NUM}", "vicon"))),
    *(("docs/results.md", rf"and the ankles {doc} mm from Vicon", "results/bench_real_gait.txt",
       rf"\| defaults \| {ref} \| [\d.]+ \| [\d.]+ \| {col} \|") for doc, ref, col in (
        (rf"{NUM}-[\d.]+", "vicon", rf"{NUM} \| [\d.]+"),
        (rf"[\d.]+-{NUM}", "markers", rf"[\d.]+ \| {NUM}"))),
    *(("docs/results.md", rf"Vicon's centres, and {doc} mm and", "results/bench_real_gait.txt",
       rf"\| pelvis width measured \| {ref} \| {col} \|") for doc, ref, col in (
        (rf"{NUM}-[\d.]+", "markers", rf"[\d.]+ \| {NUM}"),
        (rf"[\d.]+-{NUM}", "vicon", rf"[\d.]+ \| {NUM}"))),
    *(("docs/results.md", rf"mm and {doc} mm\s+with the subject", "results/bench_real_gait.txt",
       rf"\| pelvis width measured \| {ref} \| [\d.]+ \| [\d.]+ \| {col} \|")
      for doc, ref, col in ((rf"{NUM}-[\d.]+", "vicon", rf"[\d.]+ \| {NUM}"),
                            (rf"[\d.]+-{NUM}", "markers", rf"[\d.]+ \| {NUM}"))),
    ("docs/results.md", rf"the medians are {NUM}-[\d.]+° \(the two", "results/bench_real_gait.txt",
     rf"\| vqf9 \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("docs/results.md", rf"the medians are [\d.]+-{NUM}° \(the two", "results/bench_real_gait.txt",
     rf"\| pi6 \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("docs/results.md", rf"optical references' own {NUM}°\)", "results/bench_real_gait.txt",
     rf"\| optical floor \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("docs/results.md", rf"error grows by \+{NUM}°", "results/bench_real_gait.txt",
     rf"\| pelvis \| [+-][\d.]+ / \+{NUM} / "),
    ("docs/results.md", rf"the left thigh's by \+{NUM}°", "results/bench_real_gait.txt",
     rf"\| left_femur \| [+-][\d.]+ / \+{NUM} / "),
    ("docs/results.md", rf"the pelvis's path\n?\s*[\d.]+-{NUM} % of the", "results/bench_gait.txt",
     rf"\| 2 \| .* [\d.]+ / [\d.]+, {NUM} % of"),
    ("docs/results.md", rf"come {NUM}-[\d.]+ ms before Zeni", "results/bench_gait.txt",
     rf"comes {NUM}-[\d.]+ ms before Zeni"),
    ("docs/results.md", rf"come [\d.]+-{NUM} ms before Zeni", "results/bench_gait.txt",
     rf"comes [\d.]+-{NUM} ms before Zeni"),
    ("docs/results.md", rf"no push-off, {NUM} ms after it", "results/bench_gait.txt",
     rf"After it: right \+{NUM} ms"),
    ("docs/results.md", rf"initial contact {NUM} ms", "results/bench_gait.txt",
     rf"IC median \|error\| {NUM} ms"),
    ("README.md", rf"within {NUM} ms \(median\)", "results/bench_gait.txt",
     rf"IC median \|error\| {NUM} ms"),
    ("docs/results.md", rf"stride time\n?\s*{NUM} ms", "results/bench_gait.txt",
     rf"stride time median \|error\| {NUM} ms"),
    ("docs/results.md", rf"length {NUM} % \(mean absolute\)", "results/bench_gait.txt",
     rf"stride length mean \|error\| {NUM} %"),
    ("README.md", rf"lengths within\n?\s*{NUM} %", "results/bench_gait.txt",
     rf"stride length mean \|error\| {NUM} %"),
    ("docs/results.md", rf"95th percentile {NUM} cm", "results/bench_gait.txt",
     rf"95th percentile {NUM} cm \(target 5\)"),
    ("docs/results.md", rf"horizontal path {NUM} %", "results/bench_gait.txt",
     rf"mean {NUM} % of the distance"),
    ("README.md", rf"path within {NUM} % of the distance", "results/bench_gait.txt",
     rf"mean {NUM} % of the distance"),
    ("README.md", rf"IK runs {NUM}-[\d]+× faster", "results/bench_opensense.txt",
     rf"xsens_walking_orientations.sto \| 2432 \| ours \| anatomical \| hinge .* {NUM}x "),
    ("README.md", rf"IK runs [\d]+-{NUM}× faster", "results/bench_opensense.txt",
     rf"quaternions_4_ik.sto \| 1401 \| ours \| anatomical \| hinge .* {NUM}x "),
    ("docs/results.md", rf"Remounting moved the sagittal angles by at most {NUM}° RMS on\n?\s*S02",
     "results/bench_sensor_sets.txt", rf"by at most {NUM} deg RMS on S02"),
    ("docs/results.md", rf"and {NUM}° on the x-IMU3 walk", "results/bench_sensor_sets.txt",
     rf"and {NUM} deg on the x-IMU3 walk"),
    ("docs/results.md", rf"standing lean \({NUM}° on S02", "results/bench_sensor_sets.txt",
     rf"{NUM} deg without the feet's sensors"),
    ("docs/results.md", rf"remaining\s+joints by at most {NUM}°", "results/bench_sensor_sets.txt",
     rf"up to {NUM} deg on S02, and"),
    ("README.md", rf"at most {NUM}° RMS on S02 and", "results/bench_sensor_sets.txt",
     rf"by at most {NUM} deg RMS on S02"),
    ("README.md", rf"and {NUM}° on the shipped x-IMU3", "results/bench_sensor_sets.txt",
     rf"and {NUM} deg on the x-IMU3 walk"),
    ("docs/results.md", rf"the 6-D runs' median errors moved by {NUM}° \(sagittal\)",
     "results/bench_sensor_sets.txt", rf"the 6-D runs' by {NUM} and"),
    ("docs/results.md", rf"\(sagittal\) and {NUM}° \(other axes\) at\s+most",
     "results/bench_sensor_sets.txt", rf"the 6-D runs' by [\d.]+ and {NUM} deg"),
    ("docs/results.md", rf"knees' ab/adduction moves by up to {NUM}° on S02",
     "results/bench_faults.txt", rf"## S02[\s\S]*?the legs' joints move by up to {NUM} deg"),
    ("docs/results.md", rf"on S02 \({NUM}° on the simulator\)", "results/bench_faults.txt",
     rf"the legs' joints move by up to {NUM} deg"),
    ("docs/results.md", rf"without the hips' flexion axes, turned by {NUM}°",
     "results/bench_faults.txt", rf"## S02[\s\S]*?\(it turned by {NUM} deg\)"),
    ("docs/results.md", rf"rocks about once a stride by {NUM}° on S02", "results/bench_faults.txt",
     rf"## S02[\s\S]*?the axis it rocks about once a stride turned by {NUM} deg"),
    ("docs/results.md", rf"with a free ankle, {NUM}° and", "results/bench_faults.txt",
     rf"the undisturbed run measured right {NUM} deg"),
    ("docs/results.md", rf"with a free ankle, [-+\d.]+° and \+?{NUM}°", "results/bench_faults.txt",
     rf"the undisturbed run measured right [-+\d.]+ deg, left \+?{NUM} deg"),
    ("docs/results.md", rf"the foot's, {NUM} m/s² on S02", "results/bench_faults.txt",
     rf"## S02[\s\S]*?fits an ankle with femur_r_imu \(residual {NUM} m/s"),
    ("docs/results.md", rf"not the thigh's, {NUM}\)", "results/bench_faults.txt",
     rf"## S02[\s\S]*?better than with tibia_r_imu \({NUM}\)"),
    ("docs/results.md", rf"other leg's by {NUM} on S02", "results/bench_faults.txt",
     rf"## S02[\s\S]*?not with each other \(eq 2: by {NUM},"),
    ("docs/results.md", rf"and {NUM} on the simulator, of 4", "results/bench_faults.txt",
     rf"not with each other \(eq 2: by {NUM},"),
    ("docs/results.md", rf"the feet's, by {NUM} and", "results/bench_faults.txt",
     rf"## S02[\s\S]*?so read by {NUM} \(eq 3\)"),
    ("docs/results.md", rf"the feet's, by [\d.]+ and {NUM}\)", "results/bench_faults.txt",
     rf"so read by {NUM} \(eq 3\)"),
    ("docs/results.md", rf"\(cosine {NUM} on S02", "results/bench_faults.txt",
     rf"## S02[\s\S]*?named for each other \|[^|]*\|[^(]*\([\d.]+ m apart, cosine {NUM} "),
    ("docs/results.md", rf"{NUM} on the simulated walk, with the subject's right",
     "results/bench_faults.txt",
     rf"named for each other \|[^|]*\|[^(]*\([\d.]+ m apart, cosine {NUM} "),
    (_RESULTS, rf"thigh's swing\s+\({NUM}° a stride", *_realism("femur swing (deg)", 4)),
    (_RESULTS, rf"a stride against {NUM}° and", *_realism("femur swing (deg)", 1)),
    (_RESULTS, rf"a stride against [\d.]+° and {NUM}°", *_realism("femur swing (deg)", 2)),
    (_RESULTS, rf"the shank's \({NUM}° against", *_realism("tibia swing (deg)", 4)),
    (_RESULTS, rf"the shank's \([\d.]+° against {NUM}° and", *_realism("tibia swing (deg)", 1)),
    (_RESULTS, rf"the shank's \([\d.]+° against [\d.]+° and {NUM}°",
     *_realism("tibia swing (deg)", 2)),
    (_RESULTS, rf"stride time \({NUM} s against", *_realism("stride time (s)", 4)),
    (_RESULTS, rf"s against {NUM} s and [\d.]+ s\)", *_realism("stride time (s)", 1)),
    (_RESULTS, rf"s against [\d.]+ s and {NUM} s\)", *_realism("stride time (s)", 2)),
    (_RESULTS, rf"ankle's residual \({NUM} m/s²", *_realism("ankle residual (m/s^2)", 4)),
    (_RESULTS, rf"against {NUM} and [\d.]+\)\. Near", *_realism("ankle residual (m/s^2)", 1)),
    (_RESULTS, rf"against [\d.]+ and {NUM}\)\. Near", *_realism("ankle residual (m/s^2)", 2)),
    (_RESULTS, rf"swings through {NUM}° against", *_realism("pelvis swing (deg)", 4)),
    (_RESULTS, rf"swings through [\d.]+° against {NUM}°", *_realism("pelvis swing (deg)", 1)),
    (_RESULTS, rf"swings through [\d.]+° against [\d.]+° and {NUM}°",
     *_realism("pelvis swing (deg)", 2)),
    (_RESULTS, rf"turns faster \({NUM} rad/s", *_realism("femur speed (rad/s)", 4)),
    (_RESULTS, rf"rad/s against {NUM} and [\d.]+\), and", *_realism("femur speed (rad/s)", 1)),
    (_RESULTS, rf"rad/s against [\d.]+ and {NUM}\), and", *_realism("femur speed (rad/s)", 2)),
    (_RESULTS, rf"knee's centre leaves {NUM} m/s² against", *_realism("knee residual (m/s^2)", 4)),
    (_RESULTS, rf"m/s² against {NUM} and\s+[\d.]+, its hinge",
     *_realism("knee residual (m/s^2)", 1)),
    (_RESULTS, rf"m/s² against [\d.]+ and\s+{NUM}, its hinge",
     *_realism("knee residual (m/s^2)", 2)),
    (_RESULTS, rf"its hinge {NUM} rad/s against", *_realism("knee hinge residual (rad/s)", 4)),
    (_RESULTS, rf"its hinge [\d.]+ rad/s against {NUM} and",
     *_realism("knee hinge residual (rad/s)", 1)),
    (_RESULTS, rf"its hinge [\d.]+ rad/s against [\d.]+ and {NUM}",
     *_realism("knee hinge residual (rad/s)", 2)),
    (_RESULTS, rf"\({NUM} and [\d.]+ without the artefacts", *_realism("knee residual (m/s^2)", 3)),
    (_RESULTS, rf"\([\d.]+ and {NUM} without the",
     *_realism("knee hinge residual (rad/s)", 3)),
    (_RESULTS, rf"the hip\s+{NUM} against", *_realism("hip residual (m/s^2)", 4)),
    (_RESULTS, rf"the hip\s+[\d.]+ against {NUM} and", *_realism("hip residual (m/s^2)", 1)),
    (_RESULTS, rf"the hip\s+[\d.]+ against [\d.]+ and {NUM}\.",
     *_realism("hip residual (m/s^2)", 2)),
]  # fmt: skip


@pytest.mark.parametrize("doc, doc_re, result, result_re", FIGURES)
def test_a_documented_figure_is_its_results_files(doc, doc_re, result, result_re):
    quoted = re.search(doc_re, (ROOT / doc).read_text())
    assert quoted, f"{doc}: no match for {doc_re!r}"
    measured = re.search(result_re, (ROOT / result).read_text())
    assert measured, f"{result}: no match for {result_re!r}"
    assert float(quoted.group(1)) == float(measured.group(1)), (doc, quoted.group(0),
                                                                 measured.group(0))
