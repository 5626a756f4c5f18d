"""The figures the README and docs/results.md quote are the ones the benchmarks last wrote to
results/: each quoted figure is found beside the value its results file holds (issue 25: a
documented figure and its results file never disagree)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
NUM = r"(-?[\d.]+)"

_RESULTS = "docs/results.md"


def _realism(quantity: str, column: int) -> tuple[str, str]:
    """bench_sim_realism's ``quantity`` row, its ``column``-th value (1: S02, 2: the x-IMU3 walk,
    3: the ideal simulated walk, 4: the simulated walk)."""
    return ("results/bench_sim_realism.txt",
            rf"\| {re.escape(quantity)} \|" + r" [\d.]+ \|" * (column - 1) + rf" {NUM} \|")


def _brought(path: str, recording: str, column: str = "median") -> tuple[str, str]:
    """bench_real_gait's "recordings users bring" row: its median against Vicon (``median``),
    it with the walk's mean error removed (``mean removed``) or against the markers
    (``markers``)."""
    tail = {"median": rf"\*\*{NUM}\*\* \|",
            "mean removed": rf"\*\*[\d.]+\*\* \| {NUM} \|",
            "markers": rf"\*\*[\d.]+\*\* \| [\d.]+ \| {NUM} \|"}[column]
    return ("results/bench_real_gait.txt",
            rf"\| {path} \| {recording} \| [^|]+ \|" + r" [\d.]+ \|" * 6 + " " + tail)


def _live(path: str, cells: int, rate: int = 100, before: str = "") -> tuple[str, str]:
    """bench_live's table row of ``path`` at ``rate`` Hz: the figure after its first ``cells``
    cells (``before``: the words before it in its cell)."""
    return ("results/bench_live.txt",
            rf"\| {re.escape(path)} \| {rate} \|(?: [^|]+ \|){{{cells}}} {before}{NUM}")


#: (document, its regex with the figure as group 1, results file, its regex for the same figure)
_ALARMS = "results/bench_false_alarms.txt"
_REAL = "results/bench_real_gait.txt"
FIGURES = [
    (_RESULTS, rf"\(2.7° from 1120 on the vendor's, where as recorded gives {NUM}°\)",
     *_brought("vendor", "as recorded", "mean removed")),
    (_RESULTS, rf"\({NUM}° from 1120 on the vendor's",
     *_brought("vendor", "from 1120", "mean removed")),
    (_RESULTS, rf"the PI filter's [\d.]+-[\d.]+° \({NUM}°\)",
     *_brought("pi6", "as recorded", "mean removed")),
    (_RESULTS, rf"left knee's mean error at {NUM}° against the markers", _REAL,
     rf"\| vendor \| from 1120 \|(?: [^|]+ \|){{3}} [-+\d.]+ / \+?{NUM} \|"),
    (_RESULTS, rf"where Vicon's reads {NUM}°", _REAL,
     rf"\| vendor \| from 1120 \|(?: [^|]+ \|){{3}} \+?{NUM} / [-+\d.]+ \|"),
    (_RESULTS, rf"slowest neighbour's {NUM} \(", _ALARMS, rf"- moves: {NUM} on"),
    (_RESULTS, rf"flexion axis alone on its leg {NUM}°", _ALARMS, rf"- slip alone: {NUM} on"),
    (_RESULTS, rf"at most {NUM}°, below\)", _ALARMS, rf"- slip alone: {NUM} on"),
    (_RESULTS, rf"saturated samples {NUM} of the", _ALARMS, rf"- saturation: {NUM} on"),
    (_RESULTS, rf"pairing gain {NUM} at its highest", _ALARMS, rf"- crossed: {NUM} on"),
    (_RESULTS, rf"residual ratio {NUM} \(", _ALARMS, rf"- swapped: {NUM} on"),
    (_RESULTS, rf"cosine \+{NUM} at its lowest", _ALARMS, rf"- sides: {NUM} on"),
    (_RESULTS, rf"\(90° on a foot\) and qmt's walk turning into a run \({NUM}°",
     _ALARMS, rf"\| qmt's walk and run \|(?: [^|]+ \|){{4}} {NUM} \("),
    ("docs/results.md", rf"contacts\s+within {NUM} ms, stride time", "results/bench_gait.txt",
     rf"largest errors {NUM} ms"),
    ("docs/results.md", rf"stride time within {NUM} ms, length within", "results/bench_gait.txt",
     rf"largest errors [\d.]+ ms, {NUM} ms"),
    ("docs/results.md", rf"length within {NUM} %\. Each stance", "results/bench_gait.txt",
     rf"largest errors [\d.]+ ms, [\d.]+ ms, {NUM} %"),
    ("docs/results.md", rf"at up to {NUM}-[\d.]+ rad/s", "results/bench_gait.txt",
     rf"\| walk 1.8 m/s \| 200 \|.* \| {NUM} \|"),
    ("docs/results.md", rf"at up to [\d.]+-{NUM} rad/s", "results/bench_gait.txt",
     rf"\| walk 2.2 m/s \| 200 \|.* \| {NUM} \|"),
    ("README.md", rf"the median is {NUM}-[\d.]+°\s+from the vendor's",
     *_brought("vendor", "from 1300")),
    ("README.md", rf"the median is [\d.]+-{NUM}°\s+from the vendor's",
     *_brought("vendor", "from 1500")),
    ("README.md", rf"and {NUM}-[\d.]+° on every input", *_brought("pi6", "from 1120")),
    ("README.md", rf"and [\d.]+-{NUM}° on every input", *_brought("vqf6", "from 1500")),
    ("docs/results.md", rf"walk itself \(`docs/methods.md`, \"Calibrating from the walk\"\): "
     rf"median {NUM}°", *_brought("vendor", "from 1120")),
    ("docs/results.md", rf"median [\d.]+°, {NUM}° and [\d.]+°\s+from the vendor",
     *_brought("vendor", "from 1300")),
    ("docs/results.md", rf"median [\d.]+°, [\d.]+° and {NUM}°\s+from the vendor",
     *_brought("vendor", "from 1500")),
    ("docs/results.md", rf"\(VQF 6-D {NUM}-[\d.]+°, the PI", *_brought("vqf6", "from 1120")),
    ("docs/results.md", rf"\(VQF 6-D [\d.]+-{NUM}°, the PI", *_brought("vqf6", "from 1500")),
    ("docs/results.md", rf"the PI filter {NUM}-[\d.]+°\), no leg", *_brought("pi6", "from 1120")),
    ("docs/results.md", rf"the PI filter [\d.]+-{NUM}°\), no leg", *_brought("pi6", "from 1300")),
    ("docs/results.md", rf"cut recordings' medians are {NUM}-[\d.]+°",
     *_brought("vendor", "from 1120", "markers")),
    ("docs/results.md", rf"lower than as recorded \({NUM}-[\d.]+°\)",
     *_brought("vendor", "as recorded", "markers")),
    ("docs/results.md", rf"lower than as recorded \([\d.]+-{NUM}°\)",
     *_brought("pi6", "as recorded", "markers")),
    ("docs/results.md", rf"the medians are {NUM}-[\d.]+° against",
     *_brought("vqf9", "other shanks")),
    ("docs/results.md", rf"the medians are [\d.]+-{NUM}° against",
     *_brought("vendor", "other shanks")),
    ("docs/results.md", rf"vendor orientations {NUM}°", "results/bench_real_gait.txt",
     rf"\| vendor \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"VQF 9-D {NUM}°", "results/bench_real_gait.txt",
     rf"\| vqf9 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"magnetometers\) {NUM}°", "results/bench_real_gait.txt",
     rf"\| vqf6 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("docs/results.md", rf"the PI filter 6-D {NUM}°", "results/bench_real_gait.txt",
     rf"\| pi6 \| defaults \|.*\*\*{NUM}\*\* \|"),
    ("README.md", rf"median RMSE is {NUM}° from the vendor", "results/bench_real_gait.txt",
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
    ("docs/results.md", rf"find our ankles {NUM}-[\d.]+° more", "results/bench_real_gait.txt",
     r"\| vendor \|" + r" [+-][\d.]+ / [+-][\d.]+ \|" * 4 + rf" -{NUM} / "),
    ("docs/results.md", rf"find our ankles [\d.]+-{NUM}° more", "results/bench_real_gait.txt",
     r"\| pi6 \|" + r" [+-][\d.]+ / [+-][\d.]+ \|" * 5 + rf" -{NUM} / "),
    ("docs/results.md", rf"optical references' own {NUM}°\)", "results/bench_real_gait.txt",
     rf"\| optical floor \| [\d.]+ \| [\d.]+ \| {NUM} \|"),
    ("docs/results.md", rf"pelvis by only {NUM}-[\d.]+ over", "results/bench_real_gait.txt",
     rf"\| pelvis \| {NUM}, "),
    ("docs/results.md", rf"pelvis by only [\d.]+-{NUM} over", "results/bench_real_gait.txt",
     rf"\| pelvis \| [\d.]+, [\d.]+ / [\d.]+ \| [\d.]+, [\d.]+ / [\d.]+ \| {NUM}, "),
    ("docs/results.md", rf"\(its range\s+{NUM}° against", "results/bench_real_gait.txt",
     rf"\| pelvis \| [\d.]+, {NUM} / "),
    ("docs/results.md", rf"orientations \({NUM} right\)", "results/bench_real_gait.txt",
     rf"\| vendor \| [\d.]+ \*\*no\*\* \(3.5\) \|.*\| {NUM} / [\d.]+ \*\*no\*\*;"),
    ("docs/results.md", rf"the thighs' by {NUM}-[\d.]+\.", "results/bench_real_gait.txt",
     r"\| left_femur \|" + r" [\d.]+, [\d.]+ / [\d.]+ \|" * 3 + rf" {NUM}, "),
    ("docs/results.md", rf"the thighs' by [\d.]+-{NUM}\.", "results/bench_real_gait.txt",
     rf"\| left_femur \| {NUM}, "),
    ("docs/results.md", rf"° against {NUM}°\), the thighs", "results/bench_real_gait.txt",
     rf"\| pelvis \| [\d.]+, [\d.]+ / {NUM} \|"),
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
    ("docs/results.md", rf"pelvis's angles\) then move by up to {NUM}°", "results/bench_faults.txt",
     rf"## S02[\s\S]*?the pelvis's angles\) move by up to {NUM} deg"),
    ("docs/results.md", rf"the legs' joints {NUM}° on S02", "results/bench_faults.txt",
     rf"## S02[\s\S]*?the legs' joints by {NUM} \("),
    ("docs/results.md", rf"on S02, {NUM}° on the\s+simulator", "results/bench_faults.txt",
     rf"the legs' joints by {NUM} \("),
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
    ("docs/results.md", rf"two runs started into one folder: {NUM} of", "results/bench_faults.txt",
     rf"Detected and named: {NUM} of \d+ runs"),
    ("docs/results.md", rf"pelvis's joints move by up to {NUM}° RMS outside it",
     "results/bench_faults.txt", rf"Untouched joints moved by up to {NUM} deg RMS outside a gap"),
    ("docs/results.md", rf"the shank's own leg's by up to {NUM}°", "results/bench_faults.txt",
     rf"\| ending 10 s early \| VQF \|[^\n]*\| {NUM} \|\n"),
    ("docs/results.md", rf"the other joints move by {NUM}° RMS, the subject's heading",
     "results/bench_faults.txt", rf"by {NUM} with the thigh's quaternions"),
    ("docs/results.md", rf"each frame takes {NUM} ms \(p50\)", *_live("vendor", 0)),
    ("docs/results.md", rf"ms \(p50\) and {NUM} ms \(p99\)", "results/bench_live.txt",
     rf"p99 per frame \(100 Hz, 7 sensors\): {NUM} ms"),
    ("docs/results.md", rf"{NUM} ms p99 through VQF with magnetometers", *_live("VQF 9-D", 1)),
    ("docs/results.md", rf"{NUM} ms at 200 Hz", *_live("vendor", 1, 200)),
    ("docs/results.md", rf"p99 sustains {NUM} Hz", *_live("vendor", 2)),
    ("docs/results.md", rf"Once the calibration is final \({NUM} s", *_live("vendor", 3)),
    ("docs/results.md", rf"within {NUM}° RMS of `pipeline ik`'s", *_live("vendor", 4)),
    ("docs/results.md", rf"orientations, {NUM}° through VQF 9-D", *_live("VQF 9-D", 4)),
    ("docs/results.md", rf"and {NUM}° without magnetometers", *_live("VQF 6-D", 4)),
    ("docs/results.md", rf"median over every angle {NUM}°", *_live("vendor", 5)),
    ("docs/results.md", rf"every angle [\d.]+°, {NUM}° and", *_live("VQF 9-D", 5)),
    ("docs/results.md", rf"every angle [\d.]+°, [\d.]+° and {NUM}°", *_live("VQF 6-D", 5)),
    ("docs/results.md", rf"{NUM} ms through the PI filter", *_live("PI 6-D", 1)),
    ("docs/results.md", rf"{NUM}° through the PI filter \(median", *_live("PI 6-D", 4)),
    ("docs/results.md", rf"through the PI filter \(median {NUM}°", *_live("PI 6-D", 5)),
    ("docs/results.md", rf"10 minutes, {NUM} MB at the end",
     "results/bench_live.txt", rf"[\d.]+ MB after 10 minutes, {NUM} MB at the end"),
    ("docs/results.md", rf"on the whole by {NUM}° RMS in that knee's rotation",
     *_live("vendor", 7)),
    ("docs/results.md", rf"{NUM}° through VQF 9-D, and up to", *_live("VQF 9-D", 7)),
    ("docs/results.md", rf"and up to {NUM}° without magnetometers, in",
     "results/bench_live.txt", rf"\| VQF 6-D \| 100 \|(?: [^|]+ \|){{7}} [\d.]+, "
     rf"left_knee_rotation {NUM} \|"),
    ("docs/results.md", rf"{NUM} ms over the last\)", "results/bench_live.txt",
     rf"[\d.]+/{NUM} ms over the last"),
    ("docs/results.md", rf"rotation differs by up to {NUM}°",
     *_live("vendor", 6, before="left_knee_rotation ")),
    ("docs/results.md", rf"without magnetometers by {NUM}°",
     *_live("VQF 6-D", 6, before="right_knee_rotation ")),
    ("docs/results.md", rf"flat \({NUM} MB after 10 minutes", "results/bench_live.txt",
     rf"memory {NUM} MB after 10 minutes"),
    ("docs/results.md", rf"p99 {NUM} ms over the first 10 minutes", "results/bench_live.txt",
     rf"[\d.]+/{NUM} ms over the first"),
    (_RESULTS, rf"thigh's swing\s+\({NUM}° a stride", *_realism("femur swing (deg)", 4)),
    (_RESULTS, rf"a stride against {NUM}° and", *_realism("femur swing (deg)", 1)),
    (_RESULTS, rf"a stride against [\d.]+° and {NUM}°", *_realism("femur swing (deg)", 2)),
    (_RESULTS, rf"the shank's \({NUM}° against", *_realism("tibia swing (deg)", 4)),
    (_RESULTS, rf"the shank's \([\d.]+° against {NUM}° and", *_realism("tibia swing (deg)", 1)),
    (_RESULTS, rf"the shank's \([\d.]+° against [\d.]+° and {NUM}°",
     *_realism("tibia swing (deg)", 2)),
    (_RESULTS, rf"stride time at its edge \({NUM} s against", *_realism("stride time (s)", 4)),
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
]


@pytest.mark.parametrize("doc, doc_re, result, result_re", FIGURES)
def test_a_documented_figure_is_its_results_files(doc, doc_re, result, result_re):
    # the document's lines reflowed to one: a figure's phrase may break anywhere
    quoted = re.search(doc_re, " ".join((ROOT / doc).read_text().split()))
    assert quoted, f"{doc}: no match for {doc_re!r}"
    measured = re.search(result_re, (ROOT / result).read_text())
    assert measured, f"{result}: no match for {result_re!r}"
    assert float(quoted.group(1)) == float(measured.group(1)), (doc, quoted.group(0),
                                                                 measured.group(0))


@pytest.mark.slow
def test_methods_figures_of_the_shipped_ximu3_walk_are_what_a_run_gives():
    """methods.md's figures of the x-IMU3 example (no results file: computed here): VQF 9-D
    against the vendor's fusion, the knees' largest flexion, the functional calibration's halves
    and residuals."""
    from pipeline.io.formats import read_recording
    from pipeline.model.measures import Measures
    from pipeline.process.run import process_recording

    rec = read_recording("example:ximu3_lower_body")
    vendor = process_recording(rec, Measures("m", 1.8))
    vqf = process_recording(rec, Measures("m", 1.8), filter="vqf")
    text = (ROOT / "docs" / "methods.md").read_text(encoding="utf-8")
    knees, rms, r = [], [], []
    for side in ("right", "left"):
        a = np.degrees(vendor.joint_angles[f"{side}_knee_flexion"])
        b = np.degrees(vqf.joint_angles[f"{side}_knee_flexion"])
        knees += [np.nanmax(a), np.nanmax(b)]
        rms.append(np.sqrt(np.nanmean((a - b) ** 2)))
        r.append(np.corrcoef(a, b)[0, 1])
    assert min(r) > 0.99 and max(rms) < 1.0
    said = re.search(r"\(r > 0\.99, within 1° RMS, both knees to (\d+)-(\d+)°\)", text)
    assert said and (int(said[1]), int(said[2])) == (round(min(knees)), round(max(knees)))
    halves = [c.split_half_deg for c in vendor.knee_calibrations]
    res = [c.residual_rad_s for c in vendor.knee_calibrations]
    said = re.search(r"\(halves (\d+)-(\d+)° apart, residual ([\d.]+)-([\d.]+) rad/s\)", text)
    assert said and (int(said[1]), int(said[2])) == (round(min(halves)), round(max(halves)))
    assert (float(said[3]), float(said[4])) == (round(min(res), 2), round(max(res), 2))
