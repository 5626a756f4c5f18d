"""Benchmark OpenSim's OpenSense against our `.sto` IK on the same real recordings, in one run.

For each OpenSim orientation file (``shared/data/opensim``):

1. **OpenSim model**, built here with the ``opensim`` Python API, y up, x forward, z right, with
   the dimensions of our scaled model for a 1.80 m male
   (:func:`pipeline.model.scaling.geometry_from_measures`): ``ground -> pelvis`` (custom joint:
   ``pelvis_tilt`` z, ``pelvis_list`` x, ``pelvis_rotation`` y, 3 translations) ``-> femur_r/l``
   (hip custom joint Z-X-Y: ``hip_flexion`` z, ``hip_adduction`` x (-x on the left),
   ``hip_rotation`` y (-y on the left), as in OpenSim's gait models) ``-> tibia_r/l`` (knee
   ``PinJoint``, one DOF about the segment z axis) ``-> calcn_r/l`` (ankle ``PinJoint`` about z,
   ``ankle_angle`` dorsiflexion positive); ``--torso`` adds ``torso`` on a 3-DOF lumbar joint.
   Sign of ``knee_angle``: the knee pin's joint frames are turned by pi about x, so the tibia
   turns by ``Rz(-knee_angle)``: flexion is POSITIVE (Rajagopal 2015 convention, as our
   ``mot_columns``; gait2392 would be negative). Hip flexion is ``Rz(+hip_flexion)`` in both.
2. **OpenSense**: ``IMUPlacer`` (calibration pose = first sample, ``base_imu_label pelvis_imu``,
   ``base_heading_axis -z`` as in the OpenSense tutorial), then ``IMUInverseKinematicsTool`` over
   the whole trial with default weights and accuracy (1e-5), writing its ``.mot`` and orientation
   errors to a temporary folder. Timed: placement, and the IK tool's ``run()`` (which includes
   reading the ``.sto`` and writing the ``.mot``; the read alone is timed separately and is small).
   When another pelvis sensor axis points nearer our anatomical forward direction than ``-z``
   (on both files here: ``+z``, 174 deg away from ``-z``), OpenSense runs a second time with that
   ``base_heading_axis`` so that the anatomical variants are compared with a like-for-like heading.
3. **Ours**: :func:`pipeline.process.run_ik` with the same ``sensor_to_model``, heading
   ``anatomical`` (our default) and ``pelvis_imu:-z`` (OpenSense's convention), knee ``hinge``
   (1 DOF, our population knee axis, which is tilted ~14 deg from the femoral z axis, unlike
   the OpenSim pin) and ``free``. IK time: ``run.seconds_ik`` (wall) and the CPU time of the
   :func:`pipeline.ik.solver.solve_ik` call (wrapped here to read ``time.process_time``), the
   median of 5 runs.
4. **Agreement** of the joint angles (degrees) with OpenSense's ``.mot`` per coordinate: RMS
   difference and Pearson r; ranges of hip flexion and knee angle; orientation residual RMS
   (OpenSense: ``*_orientationErrors.sto``; ours: ``run.residual_rms``).

Everything single-threaded (BLAS/OpenMP threads set to 1 before the imports). Deterministic.
Skips cleanly (exit 0) when ``opensim`` is not installed.

Usage: ``python scripts/bench_opensense.py [--data DIR] [--torso] [--only FILE]`` (~50 s).
"""

from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_v] = "1"

import argparse  # noqa: E402
import contextlib  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

REPEATS = 5  # runs of each of our variants (median time reported)
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"
#: file -> OpenSense sensor_to_opensim_rotations (space-fixed X, Y, Z, rad), as its tutorial/test
FILES = {
    "quaternions_4_ik.sto": (0.0, 0.0, 0.0),
    "xsens_walking_orientations.sto": (-np.pi / 2, 0.0, 0.0),
}
VARIANTS = (("anatomical", "hinge"), ("anatomical", "free"),
            ("pelvis_imu:-z", "hinge"), ("pelvis_imu:-z", "free"))
COMPARED = ("hip_flexion", "hip_adduction", "hip_rotation", "knee_angle")
HEIGHT_M, SEX = 1.80, "m"


# ---- the OpenSim model ---------------------------------------------------------------------------
def _vec(osim, v) -> object:
    return osim.Vec3(*(float(x) for x in v))


def _custom_joint(osim, name, parent, location, child, rotations, translations=()):
    """CustomJoint: body-fixed rotations in order (coordinate, axis), then translations."""
    st = osim.SpatialTransform()
    for i, (coord, axis) in enumerate(rotations):
        ta = getattr(st, f"upd_rotation{i + 1}")()
        names = osim.ArrayStr()
        names.append(coord)
        ta.setCoordinateNames(names)
        ta.setAxis(_vec(osim, axis))
        ta.set_function(osim.LinearFunction())
    for i, (coord, axis) in enumerate(translations):
        ta = getattr(st, f"upd_translation{i + 1}")()
        names = osim.ArrayStr()
        names.append(coord)
        ta.setCoordinateNames(names)
        ta.setAxis(_vec(osim, axis))
        ta.set_function(osim.LinearFunction())
    zero = osim.Vec3(0.0)
    joint = osim.CustomJoint(name, parent, _vec(osim, location), zero, child, zero, zero, st)
    return joint


def _pin_joint(osim, name, coord, parent, location, child, flip: bool):
    """PinJoint about the segments' z axis (about -z when ``flip``: frames turned pi about x)."""
    orient = osim.Vec3(np.pi, 0.0, 0.0) if flip else osim.Vec3(0.0)
    joint = osim.PinJoint(name, parent, _vec(osim, location), orient, child, osim.Vec3(0.0), orient)
    joint.upd_coordinates(0).setName(coord)
    return joint


def build_opensim_model(osim, geometry, torso: bool = False):
    """The lower-limb OpenSim model of the module docstring, dimensions from ``geometry``."""
    m = osim.Model()
    m.setName("bench_lower_limb")
    m.setGravity(osim.Vec3(0.0, -9.80665, 0.0))
    s = geometry.mass_scale

    def body(name, mass, com, inertia):
        b = osim.Body(name, mass * s, _vec(osim, com), osim.Inertia(*inertia))
        m.addBody(b)
        return b

    pelvis = body("pelvis", 11.8, (-0.07, 0.0, 0.0), (0.1, 0.09, 0.06))
    m.addJoint(_custom_joint(
        osim, "ground_pelvis", m.getGround(), (0.0, 0.0, 0.0), pelvis,
        [("pelvis_tilt", (0, 0, 1)), ("pelvis_list", (1, 0, 0)), ("pelvis_rotation", (0, 1, 0))],
        [("pelvis_tx", (1, 0, 0)), ("pelvis_ty", (0, 1, 0)), ("pelvis_tz", (0, 0, 1))],
    ))
    for side, sx in (("right", "r"), ("left", "l")):
        g = geometry.for_side(side)
        sgn = 1.0 if side == "right" else -1.0  # OpenSim gait models: -x, -y hip axes on the left
        femur = body(f"femur_{sx}", 9.3, 0.43 * g.kjc_femur, (0.13, 0.03, 0.14))
        tibia = body(f"tibia_{sx}", 3.7, 0.43 * g.ajc_tibia, (0.05, 0.005, 0.05))
        calcn = body(f"calcn_{sx}", 1.25, (0.06, -0.04, 0.0), (0.002, 0.005, 0.005))
        m.addJoint(_custom_joint(
            osim, f"hip_{sx}", pelvis, g.hip, femur,
            [(f"hip_flexion_{sx}", (0, 0, 1)), (f"hip_adduction_{sx}", (sgn, 0, 0)),
             (f"hip_rotation_{sx}", (0, sgn, 0))],
        ))
        m.addJoint(_pin_joint(osim, f"knee_{sx}", f"knee_angle_{sx}", femur, g.kjc_femur, tibia,
                              flip=True))
        m.addJoint(_pin_joint(osim, f"ankle_{sx}", f"ankle_angle_{sx}", tibia, g.ajc_tibia, calcn,
                              flip=False))
    if torso:
        t = body("torso", 34.2, (0.0, 0.3, 0.0), (1.5, 0.75, 1.4))
        h = HEIGHT_M / 1.80
        m.addJoint(_custom_joint(
            osim, "back", pelvis, (-0.1 * h, 0.08 * h, 0.0), t,
            [("lumbar_extension", (0, 0, 1)), ("lumbar_bending", (1, 0, 0)),
             ("lumbar_rotation", (0, 1, 0))],
        ))
    m.finalizeConnections()
    cs = m.getCoordinateSet()
    for i in range(cs.getSize()):
        c = cs.get(i)
        if c.getMotionType() == 1:  # rotational: generous, unclamped ranges
            c.setRangeMin(-np.pi)
            c.setRangeMax(np.pi)
    m.initSystem()
    return m


# ---- OpenSense -----------------------------------------------------------------------------------
def read_table(path: Path) -> tuple[list[str], np.ndarray]:
    """An OpenSim .mot/.sto numeric table: (column labels, (N, ncol) array incl. time)."""
    lines = path.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.strip().lower() == "endheader")
    labels = lines[k + 1].split("\t")
    data = np.array([[float(v) for v in ln.split("\t")] for ln in lines[k + 2 :] if ln.strip()])
    return [lb.strip() for lb in labels], data


def run_opensense(osim, model, sto: Path, rot, work: Path, heading_axis: str = "-z") -> dict:
    work = work / f"opensense_{heading_axis}"
    work.mkdir()
    model_file = work / "model.osim"
    model.printToXML(str(model_file))
    rot_v = osim.Vec3(*rot)

    t0, c0 = time.perf_counter(), time.process_time()
    placer = osim.IMUPlacer()
    placer.set_model_file(str(model_file))
    placer.set_orientation_file_for_calibration(str(sto))
    placer.set_sensor_to_opensim_rotations(rot_v)
    placer.set_base_imu_label("pelvis_imu")
    placer.set_base_heading_axis(heading_axis)
    placer.run(False)
    calibrated = placer.getCalibratedModel()
    place_wall, place_cpu = time.perf_counter() - t0, time.process_time() - c0
    cal_file = work / "model_calibrated.osim"
    calibrated.printToXML(str(cal_file))

    t0, c0 = time.perf_counter(), time.process_time()
    table = osim.TimeSeriesTableQuaternion(str(sto))
    read_wall = time.perf_counter() - t0
    times = np.array(table.getIndependentColumn())

    results = work / "results"
    results.mkdir()
    ik = osim.IMUInverseKinematicsTool()
    ik.set_model_file(str(cal_file))
    ik.set_orientations_file(str(sto))
    ik.set_sensor_to_opensim_rotations(rot_v)
    ik.set_results_directory(str(results))
    ik.set_time_range(0, float(times[0]))
    ik.set_time_range(1, float(times[-1]))
    t0, c0 = time.perf_counter(), time.process_time()
    ik.run(False)
    ik_wall, ik_cpu = time.perf_counter() - t0, time.process_time() - c0

    mot = next(results.glob("*.mot"))
    labels, data = read_table(mot)
    out = {
        "time": data[:, 0],
        "columns": {lb: np.radians(data[:, i]) for i, lb in enumerate(labels) if i > 0},
        "place_wall": place_wall, "place_cpu": place_cpu, "read_wall": read_wall,
        "ik_wall": ik_wall, "ik_cpu": ik_cpu, "residual_rms": None, "sensors": None,
        "heading_axis": heading_axis,
    }
    errs = sorted(results.glob("*rror*.sto"))
    if errs:
        e_labels, e = read_table(errs[0])
        out["sensors"] = e_labels[1:]
        out["residual_rms"] = np.sqrt(np.mean(e[:, 1:] ** 2, axis=1))  # rad, per frame
    return out


# ---- ours ----------------------------------------------------------------------------------------
@contextlib.contextmanager
def timed_solve_ik(record: list, **fixed):
    """Wrap the solve_ik that pipeline.process.solve calls, to record its CPU time (``fixed``:
    keyword arguments added to the call, e.g. ``stride=1`` for the sequential solver)."""
    import pipeline.process.solve as ikmod

    original = ikmod.solve_ik

    def wrapper(*a, **kw):
        c0 = time.process_time()
        try:
            return original(*a, **kw, **fixed)
        finally:
            record.append(time.process_time() - c0)

    ikmod.solve_ik = wrapper
    try:
        yield
    finally:
        ikmod.solve_ik = original


def run_ours(trial, rot, heading: str, knee: str, work: Path, **solver) -> dict:
    from pipeline.model.measures import Measures
    from pipeline.process import mot_columns, process_recording

    cpu: list[float] = []
    walls: list[float] = []
    t0 = time.perf_counter()
    with timed_solve_ik(cpu, **solver):
        # no AoR correction: OpenSense has none, so the angles compare like for like
        for _ in range(REPEATS):  # the median of REPEATS runs: ours take ~0.1 s, so one run is
            # at the mercy of a shared machine's hiccups; OpenSense's 5-20 s average them out
            run = process_recording(trial, Measures(SEX, HEIGHT_M), knee=knee,
                                    sensor_to_model=rot, heading=heading,
                                    correction="none")
            walls.append(run.seconds_ik)
        run.skeleton.write_urdf(work / f"ours_{knee}.urdf")
    total = (time.perf_counter() - t0) / REPEATS
    return {
        "time": run.time, "columns": mot_columns(run), "ik_wall": float(np.median(walls)),
        "ik_cpu": float(np.median(cpu)), "ik_cpu_min": float(min(cpu)), "total_wall": total,
        "residual_rms": run.residual_rms,
        "right": run.heading_right, "notes": run.notes,
    }


FLOOR = "import numpy, pinocchio"


def _command_env() -> dict:
    """The environment of a command run as an installed program runs: its bytecode cached
    (``PYTHONDONTWRITEBYTECODE``, set on some machines, would make every run recompile the
    package's modules: ~0.1 s)."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def floor_command() -> float:
    """Wall time (best of 5) of the least a Python command on Pinocchio does: a new process that
    imports NumPy and Pinocchio."""
    import subprocess

    best = np.inf
    for _ in range(5):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", FLOOR], check=True, capture_output=True,
                       env=_command_env())
        best = min(best, time.perf_counter() - t0)
    return best


def whole_command(sto: Path, rot, *extra: str) -> tuple[float, float]:
    """Wall time of the whole ``pipeline ik`` command (``extra``: its flags) in a child process:
    (best, median) of 5 runs after one that caches the bytecode."""
    import subprocess

    walls = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(6):
            args = [sys.executable, "-m", "pipeline", "ik", "--orientations", str(sto), "--sex",
                    SEX, "--height-m", str(HEIGHT_M), "--out", tmp, "--overwrite",
                    *extra]
            if any(rot):
                args += ["--sensor-to-model", *(repr(float(r)) for r in rot)]
            t0 = time.perf_counter()
            subprocess.run(args, check=True, capture_output=True, env=_command_env())
            if i:
                walls.append(time.perf_counter() - t0)
    return min(walls), float(np.median(walls))


# ---- comparison ----------------------------------------------------------------------------------
def agreement(ref: dict, ours: dict, name: str) -> tuple[float, float]:
    """RMS difference (deg) and Pearson r of coordinate ``name`` on the common frames."""
    if name not in ref["columns"] or name not in ours["columns"]:
        return np.nan, np.nan
    a = np.degrees(ref["columns"][name])
    b = np.degrees(np.interp(ref["time"], ours["time"], ours["columns"][name]))
    ok = np.isfinite(a) & np.isfinite(b)
    a, b = a[ok], b[ok]
    rms = float(np.sqrt(np.mean((a - b) ** 2)))
    r = float(np.corrcoef(a, b)[0, 1]) if a.std() > 0 and b.std() > 0 else np.nan
    return rms, r


def _angle_deg(u: np.ndarray, v: np.ndarray) -> float:
    c = float(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)), -1.0, 1.0))
    return float(np.degrees(np.arccos(c)))


def _rng(cols: dict, name: str) -> str:
    if name not in cols:
        return "n/a"
    v = np.degrees(cols[name])
    return f"{np.nanmin(v):6.1f}..{np.nanmax(v):5.1f}"


def pelvis_axis_matching(trial, rot, right: np.ndarray) -> str:
    """The pelvis sensor axis (of +-x, +-y, +-z) at t0 with the largest component along the
    forward direction ``up x right`` (our anatomical heading's forward)."""
    from pipeline.io.opensim import rotate_world, sensor_to_opensim_matrix
    from pipeline.rotations import matrix_from_quat

    R0 = matrix_from_quat(
        rotate_world(trial, sensor_to_opensim_matrix(rot)).sensors["pelvis_imu"].quat[0]
    )
    up = np.array([0.0, 1.0, 0.0])
    forward = np.cross(up, right)
    best, score = "-z", -np.inf
    for sign in ("", "-"):
        for i, ax in enumerate("xyz"):
            v = (-1.0 if sign else 1.0) * R0[:, i]
            h = v - up * (v @ up)
            c = float(h @ forward)  # cos(heading difference) x horizontal length
            if c > score:
                best, score = f"{sign}{ax}", c
    return best


def _res(x) -> str:
    if x is None:
        return "n/a"
    return f"{np.degrees(np.nanmedian(x)):.2f}/{np.degrees(np.nanpercentile(x, 95)):.2f}"


def bench_file(osim, sto: Path, rot, geometry, torso: bool) -> list[str]:
    from pipeline.io.opensim import read_orientations_sto

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        model = build_opensim_model(osim, geometry, torso=torso)
        refs = {"-z": run_opensense(osim, model, sto, rot, work)}
        trial = read_orientations_sto(sto)
        ours = {v: run_ours(trial, rot, *v, work) for v in VARIANTS}
        sequential = run_ours(trial, rot, "anatomical", "free", work, stride=1)
        best = pelvis_axis_matching(trial, rot, ours[("anatomical", "free")]["right"])
        if best != "-z":  # OpenSense again, with the pelvis axis matching the anatomical heading
            refs[best] = run_opensense(osim, model, sto, rot, work, heading_axis=best)
    ref = refs["-z"]
    n, n_ours = len(ref["time"]), len(trial.time)
    fps_ref = n / ref["ik_cpu"]
    rot_s = ", ".join(f"{r:.4g}" for r in rot)
    lines = [f"\n## {sto.name}: {n} frames, sensor_to_opensim_rotations ({rot_s})"]
    for ax, r in refs.items():
        lines.append(
            f"OpenSense (base_heading_axis {ax}): placement {r['place_wall']:.2f} s wall / "
            f"{r['place_cpu']:.2f} s CPU; IK tool run() {r['ik_wall']:.2f} s wall / "
            f"{r['ik_cpu']:.2f} s CPU (incl. the .sto read, {r['read_wall']:.2f} s alone, "
            "and the .mot write)"
        )
    lines += [
        "",
        "| file | frames | solver | heading | knee | IK wall (s) | IK CPU (s) | frames/s (CPU) "
        "| frames/s (wall) | speed-up (CPU) | residual RMS median/p95 (deg) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for ax, r in refs.items():
        lines.append(
            f"| {sto.name} | {n} | OpenSense | pelvis_imu {ax} | pin | {r['ik_wall']:.2f} | "
            f"{r['ik_cpu']:.2f} | {n / r['ik_cpu']:.0f} | {n / r['ik_wall']:.0f} | "
            f"{fps_ref / (n / r['ik_cpu']):.2f}x | {_res(r['residual_rms'])} |"
        )
    rows = [(f"ours | {h} | {k}", o) for (h, k), o in ours.items()]
    rows.append(("ours, every frame in sequence (stride=1) | anatomical | free", sequential))
    for label, o in rows:
        fps = n_ours / max(o["ik_cpu"], 1e-9)
        fastest = n_ours / max(o["ik_cpu_min"], 1e-9)
        lines.append(
            f"| {sto.name} | {n_ours} | {label} | {o['ik_wall']:.3f} | "
            f"{o['ik_cpu']:.3f} | {fps:.0f} | {n_ours / max(o['ik_wall'], 1e-9):.0f} | "
            f"{fps / fps_ref:.0f}x (fastest run {fastest / fps_ref:.0f}x) | "
            f"{_res(o['residual_rms'])} |"
        )
    lines.append(
        f"(speed-up: CPU frames/s relative to OpenSense with base_heading_axis -z; ours: the "
        f"median of {REPEATS} runs, and the fastest of them: on this shared machine a 0.1 s run "
        "varies by up to 2x from one run to the next)"
    )
    free = ours[("anatomical", "free")]
    dq = max(np.nanmax(np.abs(free["columns"][c] - sequential["columns"][c]))
             for c in free["columns"] if c != "time")
    lines.append(
        f"Strided (blocks of frames, the default) vs sequential solver: largest joint-angle "
        f"difference {np.degrees(dq):.4f} deg (both within the 1e-4 rad tolerance of the optimum)"
    )
    whole, whole_med = whole_command(sto, rot)
    bare, bare_med = whole_command(sto, rot, "--no-report")
    floor = floor_command()
    os_whole = ref["place_wall"] + ref["ik_wall"]
    lines.append(
        f"Whole command: `pipeline ik` (a new process: imports, reading, calibration, AoR "
        f"correction, IK, .mot, landmarks CSV, URDF, rerun recording, summary, config, report) "
        f"{whole:.2f} s wall (best of 5; median {whole_med:.2f} s) vs OpenSense placement + IK "
        f"tool run() {os_whole:.2f} s: {os_whole / whole:.1f}x (median {os_whole / whole_med:.1f}x)"
        f" (IK only, anatomical free: "
        f"{(n_ours / max(ours[('anatomical', 'free')]['ik_cpu'], 1e-9)) / fps_ref:.0f}x)"
    )
    lines.append(
        f"Whole command without the report (`--no-report`: no matplotlib) {bare:.2f} s wall "
        f"(best of 5; median {bare_med:.2f} s): {os_whole / bare:.1f}x (median "
        f"{os_whole / bare_med:.1f}x)"
    )
    lines.append(
        f"Floor: a new process that only imports NumPy and Pinocchio takes {floor:.2f} s "
        f"(OpenSense / floor = {os_whole / floor:.1f}x); the recording is written by a child "
        "forked first thing (pipeline.viz.background) through rerun's native writer "
        "(pipeline.viz.rrd) while the parent reads, calibrates, solves and writes"
    )
    # agreement: every variant vs OpenSense -z; anatomical variants also vs OpenSense `best`
    pairs = [(v, "-z") for v in VARIANTS]
    if best != "-z":
        pairs += [(v, best) for v in VARIANTS if v[0] == "anatomical"]
    lines += [
        "",
        "Joint-angle agreement, ours vs OpenSense's .mot: RMS difference (deg) / Pearson r",
        "",
        "| coordinate | "
        + " | ".join(f"{h.split(':')[-1]} {k} vs OS {ax}" for (h, k), ax in pairs)
        + " |",
        "|---" * (len(pairs) + 1) + "|",
    ]
    for sx in ("r", "l"):
        for c in COMPARED:
            name = f"{c}_{sx}"
            cells = []
            for v, ax in pairs:
                rms, r = agreement(refs[ax], ours[v], name)
                cells.append(f"{rms:5.1f} / {r:5.2f}")
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    lines += ["", "Ranges (deg, min..max; knee flexion and hip flexion positive):", ""]
    free = ours[("anatomical", "free")]
    for sx in ("r", "l"):
        for c in ("hip_flexion", "hip_adduction", "knee_angle", "ankle_angle"):
            name = f"{c}_{sx}"
            cells = [f"OpenSense {ax} {_rng(r['columns'], name)}" for ax, r in refs.items()]
            if name in free["columns"]:
                cells.append(f"ours anatomical/free {_rng(free['columns'], name)}")
            lines.append(f"- {name}: " + "; ".join(cells))
    a, z = ours[("anatomical", "hinge")]["right"], ours[("pelvis_imu:-z", "hinge")]["right"]
    lines.append(
        f"- heading: subject's right at t0, anatomical {np.round(a, 3)} vs pelvis_imu:-z "
        f"{np.round(z, 3)}: {_angle_deg(a, z):.1f} deg apart; pelvis sensor axis nearest the "
        f"anatomical forward: {best}"
    )
    if ref["sensors"]:
        lines.append(f"- OpenSense tracked sensors (errors file): {ref['sensors']}")
    notes = sorted({(note, v) for v, o in ours.items() for note in o["notes"]})
    for note, v in notes:
        lines.append(f"- ours {v[0]}/{v[1]}: {note}")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="folder of the .sto files")
    ap.add_argument("--torso", action="store_true", help="add a torso body (8th sensor)")
    ap.add_argument("--only", choices=sorted(FILES), help="one file only")
    args = ap.parse_args()
    try:
        import opensim as osim
    except ImportError:
        print("bench_opensense: needs the opensim package (pip install opensim)", file=sys.stderr)
        return 2
    with contextlib.suppress(Exception):
        osim.Logger.setLevelString("Error")
    from pipeline.model.measures import Measures
    from pipeline.model.scaling import geometry_from_measures

    files = [f for f in FILES if args.only in (None, f)]
    missing = [f for f in files if not (args.data / f).is_file()]
    if missing:
        print(f"bench_opensense: {missing} not found in {args.data} (--data: the folder of "
              "OpenSim's .sto files, ../shared/data/opensim)", file=sys.stderr)
        return 2
    geometry, _ = geometry_from_measures(Measures(SEX, HEIGHT_M))
    print(
        f"OpenSim {osim.__version__} vs pipeline; model {SEX} {HEIGHT_M:.2f} m (thigh "
        f"{geometry.thigh_length:.3f} m, shank {geometry.shank_length:.3f} m), "
        f"{'with' if args.torso else 'no'} torso; 1 thread; frames/s = frames / CPU time"
    )
    for f in files:
        for line in bench_file(osim, args.data / f, FILES[f], geometry, args.torso):
            print(line)
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
