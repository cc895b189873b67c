"""The blind benchmark: sensors drawn at random, fitted from the recording, scored against truth.

Each session films a built-in scene with a sensor the pipeline was not written for (``seecap
record --sensor random --seed N``: thresholds, spread, refractory period, cut-off, latency,
response family, colour filter), then:

* ``full``: ``seecap fit SESSION --preset fast --time-budget 10m`` from the recording, sensor
  calibration and poses included (the end-to-end time is measured);
* ``white-box``: the same fit given the sensor's true values (every pixel's thresholds, the
  event latency, the cut-off) instead of measured ones, for as long as ``full`` trained;
* ``oracle``: the same field trained on sharp linear HDR at the true poses, as long.

Every run is scored by ``seecap fit``'s own protocol: the true test poses mapped into the fit's
frame by the training cameras' similarity, HDR after one global scale.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

from event_contrast import agreement, log_changes

from benchlib.numbers import fmt
from benchlib.plan import METHOD
from benchlib.runner import python_command, run_measured
from benchlib.tables import markdown_table
from benchlib.targets import (
    BLIND_LOG_CONTRAST,
    BLIND_ORACLE_GAP_DB,
    BLIND_POSE_MEDIAN_DEG,
    BLIND_THRESHOLD_ERROR,
    BLIND_WHITE_BOX_GAP_DB,
)
from davis_io.calibration.consistency import THRESHOLD_RANGE
from davis_io.calibration.estimate import LATENCIES_US
from davis_io.chips import DEFAULT_MODEL
from davis_io.poses.truth import compare_with_truth
from davis_io.session import DEFAULT_BINS, SensorCalibration, Session

__all__ = [
    "BLIND_SESSIONS",
    "BlindRow",
    "BlindSpec",
    "blind_report",
    "blind_rows_markdown",
    "blind_targets",
    "merged_runs",
    "row_from_runs",
    "run_blind_session",
]

VARIANTS = (METHOD, "white-box", "oracle")
EXPOSURE_S = 0.15
TIMEOUT_S = 3600.0
CONTRAST_FRAMES = 3
"""Exposures whose bins are compared with the true log change (``tools/event_contrast.py``)."""


@dataclass(frozen=True)
class BlindSpec:
    """A blind session: a scene, the seed its sensor (and shake) is drawn from, how it records.

    Attributes:
        scene: built-in scene.
        seed: draws the sensor and the shake.
        exposure_s: every frame's exposure.
        frame_interval_s: time between frame starts (0: the exposure plus 50 ms).
        event_window_ms: events kept only this near an exposure (0: every event).
        still_frames: frames mid-recording with the camera held still.
        lens: the emulator's lens (``pinhole``, ``random``: a distortion drawn from the seed).
        auto_exposure: each frame exposed for these shares of the exposure in turn (empty:
            every frame the exposure).
        camera: the emulated camera model (a DAVIS240 films its 240x180 mono array).
    """

    scene: str
    seed: int
    exposure_s: float = EXPOSURE_S
    frame_interval_s: float = 0.0
    event_window_ms: float = 0.0
    still_frames: int = 0
    lens: str = "pinhole"
    auto_exposure: tuple[float, ...] = ()
    camera: str = DEFAULT_MODEL

    @property
    def key(self) -> str:
        """Folder and row name."""
        return f"{self.scene}-s{self.seed}"

    def record_options(self) -> list[str]:
        """The ``seecap record`` options beyond scene, sensor and seed."""
        options = ["--exposure", f"{self.exposure_s:g}"]
        if self.frame_interval_s:
            options += ["--frame-interval", f"{self.frame_interval_s:g}"]
        if self.event_window_ms:
            options += ["--event-window", f"{self.event_window_ms:g}ms"]
        if self.still_frames:
            options += ["--still-frames", str(self.still_frames)]
        if self.lens != "pinhole":
            options += ["--lens", self.lens]
        if self.auto_exposure:
            options += ["--auto-exposure", ",".join(f"{share:g}" for share in self.auto_exposure)]
        if self.camera != DEFAULT_MODEL:
            options += ["--camera", self.camera]
        return options

    def describe(self) -> str:
        """How the session was recorded, in words (empty for the default way)."""
        parts = []
        if self.exposure_s != EXPOSURE_S or self.frame_interval_s:
            interval = self.frame_interval_s or self.exposure_s + 0.05
            parts.append(f"{self.exposure_s * 1000:g} ms every {interval * 1000:g} ms")
        if self.event_window_ms:
            parts.append(f"events only ±{self.event_window_ms:g} ms around exposures")
        if self.still_frames:
            parts.append(f"{self.still_frames} frames held still")
        if self.lens != "pinhole":
            parts.append(f"a {self.lens} distorted lens")
        if self.auto_exposure:
            shares = "/".join(f"{self.exposure_s * 1000 * share:g}" for share in self.auto_exposure)
            parts.append(f"an auto exposure of {shares} ms in turn")
        if self.camera != DEFAULT_MODEL:
            parts.append(f"a {self.camera}")
        return "; ".join(parts)


BLIND_SESSIONS = (
    BlindSpec("room", 10),
    BlindSpec("room", 22),
    BlindSpec("lamp", 5),
    BlindSpec("lamp", 9),
    BlindSpec("corridor", 0),
    BlindSpec("corridor", 16),
    BlindSpec("room", 101, 0.05, 0.2, event_window_ms=3),
    BlindSpec("lamp", 102, 0.02, 0.2),
    BlindSpec("corridor", 103, still_frames=4),
    BlindSpec("room", 104, 0.05, 0.2, event_window_ms=3),
    BlindSpec("lamp", 105, lens="random"),
    BlindSpec("corridor", 106, auto_exposure=(1.0, 0.5, 0.25)),
    BlindSpec("room", 107, camera="DAVIS240"),
    BlindSpec("lamp", 108, camera="DAVIS240"),
)
"""Fourteen sessions over the three scenes. The first six record as the emulator does by default
(150 ms exposures, continuous events): three monochrome (room-s22, lamp-s5, lamp-s9), three
whose pixels have no refractory period and a fast cut-off (room-s10, room-s22, corridor-s16,
where the threshold target applies), the four response families among them. The other four
record as users do, seeds 101-104 taken in order before any was fitted: view by view (events
only within 3 ms of each 50 ms exposure, a frame every 200 ms; room-s101 mono, room-s104 RGGB),
20 ms exposures every 200 ms (lamp-s102, RGGB) and four frames held still (corridor-s103).
Seed 105 records through a distorted lens drawn from its seed, fitted without its calibration
(COLMAP estimates the lens); seed 106, taken next before it was fitted, with an auto exposure
(150, 75 and 37.5 ms in turn at one gain). Seeds 107 and 108, taken next before either was
fitted, film with a DAVIS240: its 240x180 mono array behind the same focal length, so a
narrower view (46° across against 63°)."""


@dataclass
class BlindRow:
    """One blind session: its drawn sensor, what was measured, and the three fits' scores.

    Attributes:
        key: session name.
        sensor: the truth's drawn sensor values (JSON).
        calibration: the session's measured calibration (its facts).
        scores: per variant, ``hdr``, ``novel``, ``ldr`` (per exposure), ``log_contrast``,
            ``blur_px``, ``registered_hdr`` / ``registered_novel`` (the extra column),
            ``training_s``, ``steps``.
        end_to_end_s: wall time of ``seecap fit`` for ``full`` from the recording (calibration,
            poses, training, renders, scores).
        record_s: wall time of the recording.
        errors: variant -> what failed.
        event_contrast: slope of the fit's event bins on the true ln change per bin, read with
            the ``measured`` calibration and with the sensor's ``true`` values.
        recorded: how the session was recorded, when not the emulator's default way.
        poses: the estimated latent poses' errors after the similarity to the truth:
            ``rotation_median_deg``, ``rotation_max_deg``, ``registered`` (share).
    """

    key: str
    sensor: dict = field(default_factory=dict)
    calibration: dict = field(default_factory=dict)
    scores: dict = field(default_factory=dict)
    end_to_end_s: float = math.nan
    record_s: float = math.nan
    errors: dict = field(default_factory=dict)
    event_contrast: dict = field(default_factory=dict)
    recorded: str = ""
    poses: dict = field(default_factory=dict)

    @property
    def clean_pixel(self) -> bool:
        """No refractory period and a cut-off fast enough that nothing lags (above 1 kHz)."""
        dvs = self.sensor.get("dvs", {})
        return dvs.get("refractory_us", 1) == 0 and dvs.get("cutoff_hz", 0) > 1000

    def within_uncertainty(self) -> bool | None:
        """Both drawn thresholds lie within two stated uncertainties of the measured ones."""
        dvs, facts = self.sensor.get("dvs", {}), self.calibration
        try:
            return all(
                abs(facts[f"threshold_{p}"] - dvs[f"threshold_{p}"])
                <= 2 * facts[f"threshold_{p}_sd"]
                for p in ("on", "off")
            )
        except KeyError:
            return None

    def at_a_bound(self) -> bool | None:
        """A stored threshold or latency sits at its search's bound."""
        facts = self.calibration
        if not facts:
            return None
        low, high = THRESHOLD_RANGE
        thresholds = (facts["threshold_on"], facts["threshold_off"])
        return (
            min(thresholds) <= low * 1.05
            or max(thresholds) >= high * 0.95
            or facts["latency_us"] >= max(LATENCIES_US)
        )

    def threshold_errors(self) -> tuple[float, float]:
        """Measured over drawn ON and OFF thresholds, minus 1."""
        dvs = self.sensor.get("dvs", {})
        try:
            return (
                self.calibration["threshold_on"] / dvs["threshold_on"] - 1,
                self.calibration["threshold_off"] / dvs["threshold_off"] - 1,
            )
        except KeyError:
            return math.nan, math.nan


def _scores(metrics: dict) -> dict:
    training = metrics.get("training", {})
    registered = metrics.get("test_poses", {}).get("registered_scores", {})
    return {
        "hdr": metrics["hdr"]["psnr"],
        "hdr_per_channel": metrics.get("hdr_per_channel", {}).get("psnr", math.nan),
        "novel": metrics["novel_exposure"]["psnr"],
        "ldr": {exposure: score["psnr"] for exposure, score in metrics.get("ldr", {}).items()},
        "log_contrast": float(sum(metrics["log_contrast"]) / len(metrics["log_contrast"])),
        "blur_px": metrics.get("residual_blur", {}).get("sigma_px", math.nan),
        "registered_hdr": registered.get("hdr_psnr", math.nan),
        "registered_novel": registered.get("novel_exposure_psnr", math.nan),
        "training_s": training.get("elapsed_s", math.nan),
        "prepare_s": training.get("seconds_before_training", math.nan),
        "steps": training.get("steps", 0),
        "stopped": training.get("stopped", ""),
    }


def row_from_runs(key: str, session_dir: Path, timings: dict, recorded: str = "") -> BlindRow:
    """The row of a session from its runs' ``metrics.json``, calibration, poses and truth."""
    row = BlindRow(key, end_to_end_s=timings.get(METHOD, math.nan), recorded=recorded)
    row.record_s = timings.get("record", math.nan)
    with Session.open(session_dir) as session:
        truth = session.truth()
        calibration = session.calibration()
        poses = session.poses(DEFAULT_BINS)
        if truth is not None and poses is not None and poses.registered.any():
            errors = compare_with_truth(poses, session.bins(DEFAULT_BINS).split_us, truth)
            row.poses = {
                "rotation_median_deg": errors.median_rotation_deg,
                "rotation_max_deg": float(errors.rotation_deg.max()),
                "registered": float(poses.registered.mean()),
            }
    row.sensor = truth.sensor if truth is not None else {}
    row.calibration = calibration.facts() if calibration is not None else {}
    if truth is not None and calibration is not None:
        row.event_contrast = {
            "measured": _event_contrast(session_dir, calibration),
            "true": _event_contrast(session_dir, truth.sensor_calibration()),
        }
    for variant in VARIANTS:
        path = session_dir / "fit" / f"blind-{variant}" / "metrics.json"
        if path.exists():
            row.scores[variant] = _scores(json.loads(path.read_text()))
        else:
            row.errors.setdefault(variant, "no metrics.json")
    return row


def _event_contrast(session_dir: Path, calibration: SensorCalibration) -> float:
    """How much of the true ln change the bins carry when read with ``calibration``."""
    true, implied, threshold = log_changes(
        session_dir, DEFAULT_BINS, CONTRAST_FRAMES, None, calibration=calibration
    )
    return agreement(true[0], implied, threshold)["slope"]


def _fit(session_dir: Path, variant: str, budget_s: float, log_dir: Path, fresh: bool):
    argv = python_command(
        "-m",
        "davis_io.cli",
        "fit",
        str(session_dir),
        "--preset",
        "fast",
        "--variant",
        variant,
        "--time-budget",
        f"{budget_s:.0f}s",
        "--run",
        f"blind-{variant}",
    )
    return run_measured(
        [*argv, *(["--fresh"] if fresh else [])], log_dir / f"{variant}.log", timeout_s=TIMEOUT_S
    )


def run_blind_session(
    spec: BlindSpec, out: Path, budget_s: float, *, fresh: bool = False, log=print
) -> BlindRow:
    """Record one blind session (unless kept), fit the three variants (unless kept), score.

    Runs whose ``metrics.json`` is kept are read back, not trained, unless ``fresh``.
    """
    session_dir = out / "sessions" / spec.key
    log_dir = out / "logs" / spec.key
    timings_path = out / "logs" / spec.key / "timings.json"
    timings = json.loads(timings_path.read_text()) if timings_path.exists() else {}
    if fresh or not (session_dir / "truth" / "truth.h5").exists():
        usage = run_measured(
            python_command(
                "-m",
                "davis_io.cli",
                "record",
                "--emulate",
                spec.scene,
                "--sensor",
                "random",
                "--seed",
                str(spec.seed),
                *spec.record_options(),
                "--out",
                str(session_dir),
                "--overwrite",
            ),
            log_dir / "record.log",
            timeout_s=TIMEOUT_S,
        )
        timings = {"record": usage.wall_s}
        fresh = True
    for variant in VARIANTS:
        metrics = session_dir / "fit" / f"blind-{variant}" / "metrics.json"
        if metrics.exists() and not fresh:
            continue
        if variant == METHOD:
            budget = budget_s
        else:  # as long as full trained: the comparison is of the sensor values, not of time
            full = json.loads((session_dir / "fit" / "blind-full" / "metrics.json").read_text())
            budget = max(full["training"]["elapsed_s"], 1.0)
        log(f"{spec.key}: fitting {variant} for {budget:.0f} s")
        usage = _fit(session_dir, variant, budget, log_dir, fresh)
        timings[variant] = usage.wall_s
        if usage.returncode != 0:
            log(f"{spec.key}: {variant} failed (exit {usage.returncode}), see {log_dir}")
            if variant == METHOD:
                break
    timings_path.parent.mkdir(parents=True, exist_ok=True)
    timings_path.write_text(json.dumps(timings, indent=1))
    return row_from_runs(spec.key, session_dir, timings, spec.describe())


def blind_targets(row: BlindRow) -> dict[str, bool | None]:
    """The blind-camera targets of one session: met (True), missed (False) or not measured."""
    full, white, oracle = (row.scores.get(v) for v in VARIANTS)
    targets: dict[str, bool | None] = {}
    contrast = BLIND_LOG_CONTRAST
    targets[f"log contrast {contrast.goal}"] = contrast.met(full and full["log_contrast"])
    for measure in ("hdr", "novel"):
        for name, other, target in (
            ("white-box", white, BLIND_WHITE_BOX_GAP_DB),
            ("oracle", oracle, BLIND_ORACLE_GAP_DB),
        ):
            gap = other[measure] - full[measure] if full and other else None
            label = f"{name} − full {target.in_words} dB ({measure})"
            targets[label] = target.met(gap)
    median = row.poses.get("rotation_median_deg")
    targets[f"poses {BLIND_POSE_MEDIAN_DEG.in_words}° median"] = BLIND_POSE_MEDIAN_DEG.met(median)
    bound = row.at_a_bound()
    targets["no stored value at a search bound"] = None if bound is None else not bound
    targets["truth within 2 stated σ"] = row.within_uncertainty()
    errors = row.threshold_errors()
    assumed = "thresholds" in row.calibration.get("assumed", {})
    measured = row.clean_pixel and not assumed and not any(math.isnan(e) for e in errors)
    largest = max(abs(e) for e in errors) if measured else None
    limit = f"{100 * BLIND_THRESHOLD_ERROR.limit:g} %"
    targets[f"thresholds within {limit} (clean pixels, measured)"] = BLIND_THRESHOLD_ERROR.met(
        largest
    )
    return targets


def _sensor_cell(row: BlindRow) -> str:
    dvs, response = row.sensor.get("dvs", {}), row.sensor.get("response", {})
    if not dvs:
        return "-"
    return (
        f"{row.sensor.get('color_filter', '?')}, {response.get('family', '?')}, "
        f"θ {dvs['threshold_on']:.3f}/{dvs['threshold_off']:.3f} ± {dvs['threshold_sigma']:.3f}, "
        f"{dvs['cutoff_hz']:.0f} Hz, refractory {dvs['refractory_us'] / 1000:.2f} ms, "
        f"delay {row.sensor.get('event_delay_us', 0) / 1000:.1f} ms"
    )


def _measured_cell(row: BlindRow) -> str:
    facts = row.calibration
    if not facts:
        return "-"
    on, off = row.threshold_errors()
    assumed = facts.get("assumed", {})
    return (
        f"θ {facts['threshold_on']:.3f}/{facts['threshold_off']:.3f} "
        f"± {facts['threshold_on_sd']:.3f}/{facts['threshold_off_sd']:.3f} "
        f"({100 * on:+.0f} %/{100 * off:+.0f} %), latency {facts['latency_us'] / 1000:.1f} ms, "
        + ("linear" if facts.get("response_linear") else "not linear")
        + (f"; assumed: {', '.join(assumed)}" if assumed else "")
    )


def _poses_cell(row: BlindRow) -> str:
    found = row.poses
    if not found:
        return "-"
    return (
        f"{found['rotation_median_deg']:.2f}° / {found['rotation_max_deg']:.2f}° "
        f"({100 * found['registered']:.0f} % registered)"
    )


def _event_contrast_cell(row: BlindRow) -> str:
    found = row.event_contrast
    return f"{fmt(found['measured'], 2)} / {fmt(found['true'], 2)}" if found else "-"


def _gap(row: BlindRow, variant: str, measure: str) -> str:
    full, other = row.scores.get(METHOD), row.scores.get(variant)
    return fmt(other[measure] - full[measure]) if full and other else "-"


def _bracket(row: BlindRow, variant: str) -> list[str]:
    scores = row.scores.get(variant)
    if not scores:
        return ["-"] * 5
    ldr = sorted((float(exposure), psnr) for exposure, psnr in scores["ldr"].items())
    return [fmt(psnr) for _, psnr in ldr]


def blind_rows_markdown(rows: list[BlindRow]) -> str:
    """The blind benchmark's tables: sensors and calibration, scores, brackets, targets."""
    sensors = [
        [r.key, r.recorded or "default", _sensor_cell(r), _measured_cell(r), _poses_cell(r)]
        + [_event_contrast_cell(r)]
        for r in rows
    ]
    scores = []
    for r in rows:
        full = r.scores.get(METHOD)
        scores.append(
            [
                r.key,
                fmt(full["hdr"]) if full else "-",
                fmt(full["novel"]) if full else "-",
                _gap(r, "white-box", "hdr"),
                _gap(r, "white-box", "novel"),
                _gap(r, "oracle", "hdr"),
                _gap(r, "oracle", "novel"),
                fmt(full["log_contrast"], 3) if full else "-",
                fmt(full["registered_hdr"]) if full else "-",
                str(full.get("steps", "-")) if full else "-",
                fmt(r.end_to_end_s / 60, 1),
            ]
        )
    brackets = [[r.key, variant, *_bracket(r, variant)] for r in rows for variant in VARIANTS]
    target_names = list(blind_targets(rows[0])) if rows else []
    targets = [
        [r.key]
        + [{True: "met", False: "**missed**", None: "-"}[v] for v in blind_targets(r).values()]
        for r in rows
    ]
    return "\n\n".join(
        [
            markdown_table(
                [
                    "session",
                    "recorded",
                    "drawn sensor (truth)",
                    "measured (seecap calibrate)",
                    "poses: rotation error median / max",
                    "events' share of the true ln change per bin, measured / true values",
                ],
                sensors,
            ),
            markdown_table(
                [
                    "session",
                    "full HDR",
                    "full novel",
                    "white-box − full HDR",
                    "white-box − full novel",
                    "oracle − full HDR",
                    "oracle − full novel",
                    "full log contrast",
                    "full HDR, registered (extra)",
                    "full steps",
                    "full end to end, min",
                ],
                scores,
            ),
            "Every exposure of the bracket (LDR PSNR, dB; x1 is the recording's exposure):",
            markdown_table(["session", "variant", "x1/16", "x1/4", "x1", "x4", "x16"], brackets),
            markdown_table(["session", *target_names], targets),
        ]
    )


def rows_to_json(rows: list[BlindRow]) -> list[dict]:
    """JSON-safe rows."""
    return [{**asdict(r), "targets": blind_targets(r)} for r in rows]


def rows_from_json(rows: list[dict]) -> list[BlindRow]:
    """Inverse of :func:`rows_to_json` (the targets are recomputed, not read)."""
    return [BlindRow(**{k: v for k, v in row.items() if k != "targets"}) for row in rows]


def _sharing(jobs: int, threads: int) -> str:
    if jobs <= 1:
        return ""
    return (
        f" {jobs} sessions ran side by side, {threads} thread(s) per fit: each fit took fewer "
        "steps in its budget than alone would (the steps column), so its scores are if anything "
        "low."
    )


RUN_SETTINGS = ("budget_s", "jobs", "threads_per_fit")
"""What runs reported as one must share: each fit's budget and how the machine was shared."""


def merged_runs(documents: list[dict]) -> dict:
    """Several runs' ``blind.json`` documents as one: each session from the last run that has it.

    A document may itself be a merge (the published ``bench-results/blind.json``): its runs count
    one by one, in their order, so a part run again merges into what was published. The result
    keeps every run's commit, command, machine and wall time (``runs``), and the sessions each
    one's rows came from, in :data:`BLIND_SESSIONS` order; a run left with no session is dropped.

    Raises:
        ValueError: the runs gave their fits other budgets or shared the machine otherwise.
    """
    settings = {tuple(document[name] for name in RUN_SETTINGS) for document in documents}
    if len(settings) > 1:
        raise ValueError(
            f"the runs differ in {', '.join(RUN_SETTINGS)} ({sorted(settings)}): their scores "
            "do not compare in one table"
        )
    runs = [run for document in documents for run in _single_runs(document)]
    rows, source = {}, {}
    for index, (_, run_rows) in enumerate(runs):
        for row in run_rows:
            rows[row["key"]], source[row["key"]] = row, index
    keys = [spec.key for spec in BLIND_SESSIONS if spec.key in rows]
    return {
        "runs": [
            {**run, "sessions": [key for key in keys if source[key] == index]}
            for index, (run, _) in enumerate(runs)
            if index in source.values()
        ],
        **{name: documents[0][name] for name in RUN_SETTINGS},
        "rows": [rows[key] for key in keys],
    }


RUN_FACTS = ("commit", "command", "machine", "wall_s")
"""What a report states of each run beside the sessions it measured."""


def _single_runs(document: dict) -> list[tuple[dict, list[dict]]]:
    """A document's runs as (the run's facts, its rows): one for a run, several for a merge."""
    if "runs" not in document:
        return [({name: document[name] for name in RUN_FACTS}, document["rows"])]
    by_key = {row["key"]: row for row in document["rows"]}
    return [
        (
            {name: run[name] for name in RUN_FACTS},
            [by_key[key] for key in run["sessions"] if key in by_key],
        )
        for run in document["runs"]
    ]


def _provenance(document: dict) -> str:
    """Which commit, command and machine measured the report: one run, or each of several."""
    if "runs" not in document:
        return (
            f"At commit `{document['commit']}`, `{document['command']}`, on "
            f"{document['machine']}; {document['wall_s'] / 3600:.1f} h. "
        )
    runs = [
        f"* {', '.join(f'`{key}`' for key in run['sessions'])}: at commit `{run['commit']}`, "
        f"`{run['command']}`, on {run['machine']}; {run['wall_s'] / 3600:.1f} h."
        for run in document["runs"]
    ]
    return f"In {len(runs)} runs, each session from one:\n\n" + "\n".join(runs) + "\n\n"


def blind_report(document: dict) -> str:
    """The blind benchmark's section of BENCHMARKS.md from its ``blind.json`` document."""
    rows = rows_from_json(document["rows"])
    met = sum(all(v is not False for v in blind_targets(r).values()) for r in rows)
    return "\n\n".join(
        [
            "## Blind camera: sensors the pipeline was not written for",
            _provenance(document) + "Each session films a "
            "built-in scene with a sensor drawn at random (`seecap record --emulate SCENE "
            "--sensor random --seed N`); `full` is `seecap fit SESSION --preset fast "
            f"--time-budget {document['budget_s']:.0f}s` from the recording, sensor "
            "calibration and poses included; `white-box` is the same fit given the sensor's "
            "true values (every pixel's thresholds, the event latency, the cut-off, the dead "
            "time, linear frames' noise), `oracle` "
            "the same field trained on sharp HDR at the true poses, both for as long as `full` "
            "trained. PSNR in dB at the true test poses mapped by the training cameras' "
            "similarity, HDR tone-mapped after one global scale; novel = mean of the x1/4 and "
            "x4 exposures. The events' share is the least-squares slope of each bin's ln change "
            "as the fit reads it (events in light time, each weighing its pixel's threshold) on "
            "the true change, rendered from the scene at the bin's ends (`tools/event_contrast.py "
            "--calibration measured|truth`): under 1 with the true values too, the pixel lost or "
            "delayed events (a refractory period the edges outrun, a slow photoreceptor); under "
            "1 with the measured values alone, the calibration."
            + _sharing(document.get("jobs", 1), document.get("threads_per_fit", 0)),
            blind_rows_markdown(rows),
            f"{met} of {len(rows)} sessions meet every target that applies to them.",
        ]
    )
