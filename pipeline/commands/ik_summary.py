"""The ``_summary.md`` of a ``pipeline ik`` run: its inputs, sensor checks, calibrations and
corrections, strides and angle ranges, and the notes (:func:`summary_text`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.analysis.cycles import cycle_angles, cycle_table
from pipeline.analysis.strides import stride_table
from pipeline.calibration.conventions import DEFAULT_FILTER
from pipeline.io.formats import recording_name
from pipeline.io.sensor_names import MODEL_FRAME_NAMES
from pipeline.process.run import IKRun

__all__ = ["summary_text"]


def summary_text(run: IKRun, name: str | None = None) -> str:
    """The run's ``_summary.md``: inputs, quality flags, corrections, calibrations, ranges;
    ``name``: its outputs' (default: the recording's)."""
    source = Path(run.inputs.orientations) if run.inputs else Path(run.source or "recording")
    measures = run.measures
    name = name or recording_name(source)
    fps = len(run.time) / max(run.seconds_ik, 1e-9)
    o = run.options
    what = "segment orientations" if o.segment_orientations else "sensor orientations"
    if run.filtered:
        by = (o.filter or DEFAULT_FILTER).upper()
        what = f"raw signals, orientations by {by} ({run.filtered})"
    lines = [
        f"# IK of {name} ({source.name})" if name != source.name else f"# IK of {name}",
        "",
        *(f"**WARNING: {flag}**\n" for flag in run.flags),
        f"- subject: sex {measures.sex}, height {measures.height_m:.2f} m; model: {name}.urdf "
        f"(knee {o.knee})",
        f"- sensors observe: {', '.join(run.sensors.joints)}; input: {what}",
        f"- calibration: {run.calibration}",
        f"- {len(run.time)} frames, {run.time[-1] - run.time[0]:.2f} s; IK {run.seconds_ik:.2f} s "
        f"({fps:.0f} frames/s)",
        f"- heading: {run.heading_method}; subject's right at the calibration pose (world): "
        + "("
        + ", ".join(f"{v:.3f}" for v in run.heading_right)
        + ")",
        f"- orientation residual RMS: median {np.degrees(np.nanmedian(run.residual_rms)):.2f} deg, "
        f"95th percentile {np.degrees(np.nanpercentile(run.residual_rms, 95)):.2f} deg",
        f"- knee AoR correction: {o.correction}",
    ]
    lines += _sensor_table(run)
    if run.corrections:
        lines += _correction_table(run)
    if run.heading_drifts:
        lines += ["", f"Sensor headings aligned by the joints (`--drift {o.drift}`; the distal "
                  "sensor turned into the proximal one's heading, deg; a `thigh` row: without a "
                  "pelvis sensor, into the other thigh's):", "",
                  "| joint | from | to | drift | constraint residual | with a constant heading |",
                  "|---|---|---|---|---|---|"]
        for key, d in run.heading_drifts.items():
            lines.append(f"| {key.replace('_', ' ')} | {np.degrees(np.nanmin(d.psi)):.1f} | "
                         f"{np.degrees(np.nanmax(d.psi)):.1f} | {d.drift_deg:.1f} | "
                         f"{d.residual_deg:.2f} | {d.before_deg:.2f} |")
        lines.append("")
    if run.knee_calibrations:
        lines += ["", "Functional knee calibration from the raw signals (Hu 2021, "
                  f"{o.calibration_method}; with `--correction functional` a trusted knee is "
                  "corrected towards its hinge axis):", "",
                  "| knee | axis in thigh sensor | axis in shank sensor | halves apart (deg) | "
                  "hinge residual (rad/s) | vs model axis (deg) | trusted | used |",
                  "|---|---|---|---|---|---|---|---|"]
        for c in run.knee_calibrations:
            def v(a):
                return "(" + ", ".join(f"{x:.3f}" for x in a) + ")"

            corr = run.corrections.get(c.side)
            if corr is not None and corr.method == "functional":
                used = "yes"
            elif o.correction == "functional":  # not trusted
                used = "no: corrected by the AoR its orientations show (eq 1-8)"
            else:
                used = f"no: correction {o.correction}"
            lines.append(f"| {c.side} | {v(c.axis_thigh)} | {v(c.axis_shank)} | "
                         f"{c.split_half_deg:.1f} | {c.residual_rad_s:.3f} | {c.vs_model_deg:.1f} "
                         f"| {'yes' if c.trusted else 'no: ' + c.reason} | {used} |")
        lines.append("")
    if run.gait.strides:
        sources = "; ".join(f"{side}: {src}" for side, src in run.gait.sources.items())
        lines += ["", f"Strides (`<name>_strides.csv`; events and foot paths from {sources}; "
                  "the means over the straight, steady strides, the others counted):",
                  "", *stride_table(run.gait.strides), ""]
        cycles = cycle_angles(run.time, run.joint_angles, run.gait.strides)
        lines += ["Joint angles over the gait cycle (`<name>_cycles.csv`: each stride at 0-100 % "
                  "of its time; here each curve's maximum, minimum and range, mean ± SD over the "
                  "same strides):", "", *cycle_table(cycles), ""]
    if not any(j.endswith("_ankle") for j in run.sensors.joints):
        lines.append("- no foot sensors: the ankle is held neutral and not reported")
    lines += ["", "| angle | min (deg) | max (deg) |", "|---|---|---|"]
    for k, v in run.joint_angles.items():
        lines.append(f"| {k} | {np.degrees(np.nanmin(v)):.1f} | {np.degrees(np.nanmax(v)):.1f} |")
    if run.notes:
        lines += ["", "Notes:", ""] + [f"- {n}" for n in run.notes]
    return "\n".join(lines) + "\n"


def _sensor_table(run: IKRun) -> list[str]:
    """One row per sensor: the sensor check's findings and the magnetometer's trust."""
    found: dict[str, list] = {}
    for f in run.sensor_findings:
        found.setdefault(f.sensor, []).append(f)
    used_names = {MODEL_FRAME_NAMES.get(frame, frame) for frame in run.placements}
    names = sorted(used_names | set(found) | set(run.magnetometers))
    lines = ["", "Sensor checks (`pipeline.process.sensor_checks`: what the reader repaired in "
             "the sensor's file, dead channels, dropouts, saturation, units, moving with the "
             "segment, slipping on it; magnetometers against the other sensors' field):",
             "", "| sensor | checks | magnetometer | used |", "|---|---|---|---|"]
    for n in names:
        fs = found.get(n, [])
        checks = "; ".join(f"{f.check}: {f.evidence} ({f.action})" for f in fs) or "ok"
        m = run.magnetometers.get(n)
        mag = "-" if m is None else ("trusted" if m.trusted else f"not trusted: {m.evidence}")
        used = "no: excluded, its joints not written" if any(
            f.action == "excluded" for f in fs) else "yes"
        lines.append(f"| {n} | {checks} | {mag} | {used} |")
    return lines + [""]


def _correction_table(run: IKRun) -> list[str]:
    def vec(v) -> str:
        return "-" if v is None else "(" + ", ".join(f"{x:.3f}" for x in v) + ")"

    def rot(rv) -> str:
        angle = float(np.degrees(np.linalg.norm(rv)))
        axis = rv / np.linalg.norm(rv) if angle > 0 else np.zeros(3)
        return f"{angle:.1f} deg about {vec(axis)}"

    lines = ["", "| knee | AoR seen (femur; tibia frame) | reference AoR | femur correction | "
             "tibia correction | hinge residual before -> after (deg) |",
             "|---|---|---|---|---|---|"]
    for side, c in run.corrections.items():
        seen = f"{vec(c.measured_femur_axis)}; {vec(c.measured_tibia_axis)}"
        if c.method == "functional":
            seen += " (functional calibration)"
        elif c.method == "population":
            seen = f"not seen ({c.reason}): corrected as the reference population's knee"
        if c.halves_apart is not None:
            seen += f"; the walk's halves' corrections {np.degrees(c.halves_apart):.1f} deg apart"
        ref = f"{vec(c.reference_femur_axis)}; {vec(c.reference_tibia_axis)}"
        if c.applied:
            fem, tib = rot(c.femur_axis_angle), rot(c.tibia_axis_angle)
        else:
            fem = tib = f"not applied: {c.reason}"
        lines.append(f"| {side} | {seen} | {ref} | {fem} | {tib} | "
                     f"{np.degrees(c.hinge_residual_before):.1f} -> "
                     f"{np.degrees(c.hinge_residual_after):.1f} |")
    return lines + [""]
