"""Every sensor check's statistic against its limit on faultless recordings (the false-alarm
margin): whether any check would exclude a good sensor.

A check that excludes a sensor must be certain: its statistic on every faultless recording here
should sit clear of the limit at which it excludes (or flags). Per recording, the run's sensor
findings (``pipeline ik`` defaults, raw signals through the default filter where the recording
has them) and each check's statistic at its worst sensor:

* ``saturation``: the largest share of samples beyond a human segment's speed or held at a
  range's limit (excluded above ``MAX_SATURATED``);
* ``dropout``: the largest share of a sensor's samples missing (excluded from ``MAX_MISSING``);
* ``moves``: the smallest ratio of a sensor's angular speed to its slowest neighbour's
  (``moves with its segment``: excluded or noted below ``MIN_SPEED_RATIO``);
* ``slip``: the largest step of a sensor's view of its segment that counts as alone on its leg,
  its flexion axis's (excluded beyond ``CERTAIN_SLIP_DEG``, flagged beyond ``SLIP_DEG``), and
  the largest step of all (alone or not);
* ``crossed``: eq 2's pairing gain (the shanks' or feet's sensors exchanged from ``MIN_GAIN``;
  the four excluded where the thighs' eq 3 is under ``MIN_THIGH_GAIN``);
* ``swapped``: a leg's thigh and shank, the shank's ankle residual over the thigh's
  (swapped beyond ``SWAP_RATIO``);
* ``sides``: eq 1's cosine (the legs read back as mirrored below ``-MIN_MARGIN``).

Recordings: S02 (as recorded; its other shank sensors; cut to its first strides, its last
strides, and to start at samples 1120, 1300, 1500), the x-IMU3 walk, qmt's walk and run,
OpenSense's walk (orientations only), BROAD's trials (one sensor: its own checks), and simulated
walks (20 s after 3 s standing, and short walkways of 3-4 strides).

Run alone (2 cores): ``python scripts/bench_false_alarms.py`` -> ``results/bench_false_alarms.txt``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from bench_gait import S02_MAP  # noqa: E402
from real_gait_cuts import other_shanks  # noqa: E402

from pipeline.errors import InputError  # noqa: E402
from pipeline.io.recording import Recording  # noqa: E402
from pipeline.model.measures import Measures  # noqa: E402
from pipeline.process import process_recording  # noqa: E402
from pipeline.process import run as run_module  # noqa: E402
from pipeline.process import signal_checks as sc  # noqa: E402
from pipeline.process.check_context import CheckContext  # noqa: E402
from pipeline.process.options import IKOptions  # noqa: E402
from pipeline.process.sides import MIN_MARGIN  # noqa: E402
from pipeline.process.slip import slip_step  # noqa: E402
from pipeline.process.slip_step import (  # noqa: E402
    ALONE_DEG,
    CERTAIN_SLIP_DEG,
    MAX_STRIDE_S,
    ROCKING_AXIS,
    SLIP_DEG,
)
from pipeline.process.swap import (  # noqa: E402
    MIN_GAIN,
    MIN_THIGH_GAIN,
    SWAP_RATIO,
    crossing_evidence,
    swap_evidence,
)

VENDOR = IKOptions(sensor_to_model=(-np.pi / 2, 0.0, 0.0))
Case = tuple[str, Callable[[], Recording | None], Measures, IKOptions]


def _s02(data: Path) -> Iterator[Case]:
    from pipeline.io.formats import read_recording

    folder = data / "gaittoolbox_s02"
    if not folder.exists():
        return
    s02 = read_recording(folder / "imu", S02_MAP)
    m = Measures("m", 1.72)
    yield "S02 as recorded", lambda: s02, m, VENDOR
    yield "S02, its other shank sensors", lambda: other_shanks(folder, S02_MAP), m, VENDOR
    yield "S02, its first strides (to 14 s)", lambda: s02.cropped(0, 1400), m, VENDOR
    yield "S02, its last strides (from 16 s)", lambda: s02.cropped(1600), m, VENDOR
    for start in (1120, 1300, 1500):
        yield f"S02 from sample {start}", (lambda a=start: s02.cropped(a)), m, VENDOR


def _others(data: Path) -> Iterator[Case]:
    from _helpers import qmt_recording

    from pipeline.io.formats import read_recording

    yield ("the x-IMU3 walk (shipped)", lambda: read_recording("example:ximu3_lower_body"),
           Measures("m", 1.8), IKOptions())
    if (data / "qmt_full_body").exists():
        yield ("qmt's walk and run", lambda: qmt_recording(data), Measures("m", 1.75),
               IKOptions())
    sto = data / "opensim" / "xsens_walking_orientations.sto"
    if sto.exists():
        yield ("OpenSense's walk (orientations)", lambda: read_recording(sto), Measures("m", 1.8),
               VENDOR)


def _simulated() -> Iterator[Case]:
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    m = Measures("m", 1.75)
    sk = Skeleton.build(geometry_from_measures(m)[0], knee="free", root="freeflyer",
                        ankle="free")

    def walk(seed: int, duration: float, standing: float) -> Recording:
        return simulate_trial(sk, "walk", duration_s=duration, seed=seed, standing_s=standing,
                              artefacts=Artefacts()).raw_recording()

    for seed in (0, 1, 2):
        yield f"simulated walk, seed {seed} (20 s)", (lambda s=seed: walk(s, 20.0, 3.0)), m, \
            IKOptions()
    for seed in (0, 1):
        yield (f"simulated short walkway, seed {seed} (6 s)", (lambda s=seed: walk(s, 6.0, 2.0)),
               m, IKOptions())


def _broad(data: Path) -> Iterator[Case]:
    """BROAD's trials: one sensor (a shank's name: only its own checks apply)."""
    folder = data / "broad"
    for f in sorted(folder.glob("*.mat")) if folder.exists() else []:
        yield f"BROAD {f.stem}", (lambda f=f: _broad_recording(f)), Measures("m", 1.75), \
            IKOptions()


def _broad_recording(path: Path) -> Recording:
    import scipy.io as sio

    from pipeline.io.recording import SensorSignals

    d = sio.loadmat(path, squeeze_me=True)
    rate = float(d["sampling_rate"])
    n = len(d["imu_gyr"])
    return Recording(np.arange(n) / rate, rate, {"tibia_r_imu": SensorSignals(
        gyr=np.asarray(d["imu_gyr"], float), acc=np.asarray(d["imu_acc"], float))})


def _cases(data: Path) -> Iterator[Case]:
    yield from _s02(data)
    yield from _others(data)
    yield from _broad(data)
    yield from _simulated()


Worst = tuple[float, str] | None  # a check's worst value on a recording, and its sensor


def _worst(values: list[tuple[float, str]], largest: bool = True) -> Worst:
    """The worst value and its sensor, or None."""
    return (max if largest else min)(values) if values else None


def _shown(worst: Worst, fmt: str = "{:.3g}") -> str:
    return "-" if worst is None else f"{fmt.format(worst[0])} ({worst[1]})"


def _share_stats(ctx: CheckContext) -> tuple[Worst, Worst]:
    """Saturation's and dropout's largest shares."""
    sat, gone = [], []
    for name in ctx.rec.sensors:
        found = sc.saturation(ctx.own(name), ctx.rec.rate_hz)
        sat.append((0.0 if found is None else found[0], name))
        spans = ctx.missing.spans.get(name) or []
        gone.append((sum(b - a for a, b in spans) / ctx.rec.n_samples, name))
    return _worst(sat), _worst(gone)


def _moves_stat(ctx: CheckContext) -> Worst:
    """The smallest speed ratio of a sensor to its slowest moving neighbour."""
    ratios = [(found[0], name) for name in ctx.rec.sensors
              if (found := sc.speed_ratio(name, ctx)) is not None]
    return _worst(ratios, largest=False)


def _slip_stats(ctx: CheckContext) -> tuple[Worst, Worst]:
    """The largest flexion-axis step alone on its leg (a leg sensor's), the largest of all."""
    alone, every = [], []
    for name in ctx.rec.sensors:
        step = slip_step(name, ctx)
        if step is None or not np.isfinite(step.deg):
            continue
        every.append((step.deg, name))
        if _alone(step) and step.axis_name != ROCKING_AXIS and np.isfinite(step.axis_deg):
            alone.append((step.axis_deg, name))
    return _worst(alone), _worst(every)


def _alone(step) -> bool:
    """Whether a step counts as a slip's, whatever its size: alone on its leg or on its side of
    the body, within a walk (:attr:`~pipeline.process.slip_step.Slip.slipped` but its size)."""
    together = step.mirror_deg < ALONE_DEG and step.others_min_deg < ALONE_DEG
    return step.pause_s <= MAX_STRIDE_S and (step.others_deg < ALONE_DEG or together)


def _pairing_stats(ctx: CheckContext) -> tuple[Worst, str, Worst]:
    """Eq 2's gain, it and eq 3's shown, and the thigh/shank swap's largest residual ratio."""
    crossing = crossing_evidence(ctx)
    gain = None if crossing is None else (crossing.pairing, "legs")
    shown = "-" if crossing is None else f"{crossing.pairing:+.2f} ({crossing.thighs:+.2f})"
    ratios = []
    for side in ("right", "left"):
        swap = swap_evidence(side, ctx.rec)
        if swap is not None and swap.thigh_residual > 0:
            ratios.append((swap.shank_residual / swap.thigh_residual, f"{side} leg"))
    return gain, shown, _worst(ratios)


def _run(rec: Recording, measures: Measures, opts: IKOptions) -> tuple[list, float | None]:
    """The run's sensor findings and eq 1's cosine (the sides check, seen as it runs)."""
    seen = []
    original = run_module.side_evidence

    def watched(*args, **kwargs):
        out = original(*args, **kwargs)
        seen.append(out)
        return out

    run_module.side_evidence = watched
    try:
        run = process_recording(rec, measures, opts)
    except InputError as e:
        return [f"refused: {e}"], None
    finally:
        run_module.side_evidence = original
    return run.sensor_findings, next((s.margin for s in seen if s is not None), None)


def _findings(found) -> str:
    """The run's exclusions and flags (a check's 'listed' notes, saying what it did not check,
    left out)."""
    if found and isinstance(found[0], str):
        return found[0]
    shown = [f"{f.sensor} {f.check}: {f.action.value}" for f in found
             if f.action.value not in ("listed",)]
    return "; ".join(shown) or "none"


#: Each check's limit, whether it acts above it (else below), and what it does there.
LIMITS = {"saturation": (sc.MAX_SATURATED, True, "excludes"),
          "dropout": (sc.MAX_MISSING, True, "excludes"),
          "moves": (sc.MIN_SPEED_RATIO, False, "excludes or notes"),
          "slip alone": (CERTAIN_SLIP_DEG, True, "excludes"),
          "crossed": (MIN_GAIN, True, "reads back or excludes"),
          "swapped": (SWAP_RATIO, True, "reads back"),
          "sides": (-MIN_MARGIN, False, "reads back")}


def row(label: str, rec: Recording, measures: Measures, opts: IKOptions
        ) -> tuple[str, dict[str, Worst]]:
    """One recording's row of the table and its checks' worst values (a single sensor: its own
    signals' checks alone)."""
    ctx = CheckContext.of_recording(rec)
    sat, gone = _share_stats(ctx)
    worst = {"saturation": sat, "dropout": gone}
    if len(rec.sensors) == 1:
        return (f"| {label} | {_shown(sat)} | {_shown(gone)} | - | - | - | - | - | - | one "
                "sensor: no joint to run, its own signals' checks only |"), worst
    alone, every = _slip_stats(ctx)
    gain, crossed, swapped = _pairing_stats(ctx)
    found, sides = _run(rec, measures, opts)
    worst.update({"moves": _moves_stat(ctx), "slip alone": alone, "crossed": gain,
                  "swapped": swapped, "sides": None if sides is None else (sides, "legs")})
    cosine = "-" if sides is None else f"{sides:+.2f}"
    return (f"| {label} | {_shown(sat)} | {_shown(gone)} | {_shown(worst['moves'])} | "
            f"{_shown(alone, '{:.1f}')} | {_shown(every, '{:.1f}')} | {crossed} | "
            f"{_shown(swapped, '{:.2f}')} | {cosine} | {_findings(found)} |"), worst


def closest(rows: list[tuple[str, dict[str, Worst]]]) -> list[str]:
    """Per check, the recording whose statistic came nearest its limit."""
    out = []
    for check, (limit, above, does) in LIMITS.items():
        seen = [(w[0], label) for label, ws in rows if (w := ws.get(check)) is not None]
        if not seen:
            continue
        value, label = (max if above else min)(seen)
        out.append(f"- {check}: {value:.3g} on {label} (it {does} "
                   f"{'above' if above else 'below'} {limit:g})")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("../shared/data"))
    ap.add_argument("--out", type=Path, default=Path("results/bench_false_alarms.txt"))
    args = ap.parse_args()
    lines = [
        "# Sensor checks on faultless recordings: each statistic at its worst sensor against "
        "its limit (scripts/bench_false_alarms.py)", "",
        f"Limits: saturation excludes above {sc.MAX_SATURATED:g} of the samples; dropout "
        f"excludes from {sc.MAX_MISSING:g}; moves (speed over the slowest neighbour's) excludes "
        f"or notes below {sc.MIN_SPEED_RATIO:g}; slip flags beyond {SLIP_DEG:g} deg alone on its "
        f"leg and excludes a leg sensor's flexion axis beyond {CERTAIN_SLIP_DEG:g}; crossed reads "
        f"back from a gain of {MIN_GAIN:g} (the four excluded where the thighs' |eq 3| < "
        f"{MIN_THIGH_GAIN:g}); swapped from a residual ratio of {SWAP_RATIO:g}; sides reads the "
        f"legs back below {-MIN_MARGIN:+g}. '-': the check does not apply (too few strides, "
        "sensors or signals).", "",
        "| recording | saturation | dropout | moves | slip alone (axis, deg) | largest step (deg) "
        "| crossed: eq 2 (eq 3) | swapped: ratio | sides: cosine | the run's findings |",
        "|---|---|---|---|---|---|---|---|---|---|"]
    rows = []
    for label, make, measures, opts in _cases(args.data.resolve()):
        rec = make()
        if rec is None:
            continue
        line, worst = row(label, rec, measures, opts)
        rows.append((label, worst))
        lines.append(line)
        print(line, flush=True)
    excluded = [line for line in lines if line.startswith("| ") and ": excluded" in line]
    lines += ["", f"Sensors excluded on these faultless recordings: {len(excluded)}. Nearest "
              "approach to each limit:", "", *closest(rows)]
    args.out.write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
