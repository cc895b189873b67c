"""``RUN/report.html``: one static, self-contained page of a fit, written from its run folder.

The input frames (or, for an emulated session, the truth) beside the renders at the same poses,
an exposure slider over the LDR renders, the HDR views, the training curve, the responses, the
calibration with each value marked measured or assumed, the camera path, the scores with their
protocol and the software that made them. Every image is embedded, so the page opens anywhere.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import cv2
import numpy as np

from davis_io.session import Session, output_errors
from seenerf.eval.plots import camera_path_plot
from seenerf.eval.scores import format_scores

__all__ = ["REPORT_NAME", "REPORT_VIEWS", "is_session_run", "write_report"]

REPORT_NAME = "report.html"
REPORT_VIEWS = 8
"""Views shown at most (evenly spaced), so that a long session's page stays a few megabytes."""
JPEG_QUALITY = 92


def is_session_run(run_dir: Path | str) -> bool:
    """True for a run folder of a session (``SESSION/fit/RUN``), which a report can be made of."""
    return (Path(run_dir).parent.parent / "session.json").exists()


def write_report(run_dir: Path | str) -> Path:
    """Write ``RUN/report.html`` from the run's files and its session; return its path."""
    run_dir = Path(run_dir)
    session_dir = run_dir.parent.parent
    metrics = _json(run_dir / "metrics.json")
    saved = _json(run_dir / "config.json")
    ldr_dirs = sorted((run_dir / "renders" / "ldr").glob("*"), key=lambda p: float(p.name))
    names = sorted(p.stem for p in (run_dir / "renders" / "hdr").glob("*.png"))
    shown = [names[i] for i in _spread(len(names), REPORT_VIEWS)]
    path_png = run_dir / "camera-path.png"
    with Session.open(session_dir) as session:
        references, reference_what = _references(session, shown, ldr_dirs)
        calibration = session.calibration()
        poses = session.poses(int(saved.get("bins", 0))) if saved.get("bins") else None
    if poses is not None:
        camera_path_plot(path_png, poses.c2w[..., :3, 3], poses.registered)
    page = _page(
        title=f"{session_dir.name} / {run_dir.name}",
        metrics=metrics,
        saved=saved,
        views=[
            {
                "name": name,
                "reference": references.get(name),
                "hdr": _view_uri(run_dir / "renders" / "hdr" / f"{name}.png"),
                "ldr": [_view_uri(folder / f"{name}.png") for folder in ldr_dirs],
            }
            for name in shown
        ],
        exposures=[folder.name for folder in ldr_dirs],
        reference_what=reference_what,
        figures={
            "training": _png_uri(run_dir / "training.png"),
            "responses": _png_uri(run_dir / "crf.png"),
            "camera path": _png_uri(path_png),
        },
        calibration=calibration,
    )
    out = run_dir / REPORT_NAME
    with output_errors(out):
        out.write_text(page, encoding="utf-8")
    return out


def _json(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def _spread(count: int, most: int) -> list[int]:
    """Up to ``most`` indices spread evenly over ``count``."""
    if count <= most:
        return list(range(count))
    return sorted({int(round(i)) for i in np.linspace(0, count - 1, most)})


def _png_uri(path: Path) -> str | None:
    """A figure file as it is (a plot: PNG keeps its lines sharp); None when missing."""
    try:
        return "data:image/png;base64," + base64.b64encode(path.read_bytes()).decode("ascii")
    except OSError:
        return None


def _view_uri(path: Path) -> str | None:
    """A rendered view as a JPEG (quality 92): a tenth of its PNG's size, for a page of many."""
    image = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if image is None:
        return None
    ok, encoded = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    return "data:image/jpeg;base64," + base64.b64encode(encoded.tobytes()).decode("ascii")


def _array_uri(image: np.ndarray) -> str:
    """A JPEG data URI of an 8-bit image (grey ``(H, W)`` or RGB ``(H, W, 3)``)."""
    pixels = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2BGR)
    ok, encoded = cv2.imencode(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    return "data:image/jpeg;base64," + base64.b64encode(encoded.tobytes()).decode("ascii")


def _references(session: Session, shown: list[str], ldr_dirs: list[Path]):
    """What each rendered view is compared with: the truth's image or the recorded frame."""
    truth = session.truth()
    if truth is not None and len(truth.test_ldr):
        recorded = float(np.median(session.frames_table().exposure_us)) * 1e-6
        exposures = np.asarray(truth.test_exposures_s, np.float64)
        index = int(np.argmin(np.abs(np.log(exposures / recorded))))
        images = {
            name: _array_uri(_eight_bit(truth.test_ldr[int(name), index]))
            for name in shown
            if int(name) < len(truth.test_ldr)
        }
        return images, f"the truth at {exposures[index]:g} s (the recording's exposure)"
    usable = np.flatnonzero(~np.asarray(session.frames_table().events_lost, bool))
    images = {}
    for name in shown:
        if int(name) < len(usable):
            frame = session.frame(int(usable[int(name)]))
            scale = 255.0 / float(2**frame.bit_depth - 1)
            images[name] = _array_uri(np.clip(frame.image * scale, 0, 255).astype(np.uint8))
    return images, "the recorded frame (blurred, at the recording's exposure)"


def _eight_bit(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.dtype != np.uint8:
        image = np.clip(np.round(image * 255), 0, 255).astype(np.uint8)
    return image[..., 0] if image.ndim == 3 and image.shape[2] == 1 else image


def _calibration_rows(calibration) -> str:
    if calibration is None:
        return "<p>The session has no calibration.</p>"
    facts = calibration.facts()
    assumed = facts.pop("assumed", {})
    facts.pop("method", None)
    groups = {
        "thresholds": ("threshold_on", "threshold_off", "threshold_on_sd", "threshold_off_sd"),
        "threshold_scale": ("threshold_on", "threshold_off"),
        "latency_us": ("latency_us",),
        "dead_time_us": ("dead_time_us",),
        "response": ("response_linear", "black_level", "noise_gain", "noise_floor"),
        "pixel_factors": (),
    }
    assumed_fields = {
        field: why for name, why in assumed.items() for field in groups.get(name, (name,))
    }
    rows = []
    for name, value in facts.items():
        why = assumed_fields.get(name)
        state = (
            f'<td class="assumed">assumed: {html.escape(why)}</td>' if why else "<td>measured</td>"
        )
        shown = f"{value:.4g}" if isinstance(value, float) else html.escape(str(value))
        rows.append(f"<tr><td>{html.escape(name)}</td><td>{shown}</td>{state}</tr>")
    if "pixel_factors" in assumed:
        why = html.escape(assumed["pixel_factors"])
        rows.append(
            f'<tr><td>pixel factors</td><td>1</td><td class="assumed">assumed: {why}</td></tr>'
        )
    return (
        "<table><tr><th>value</th><th></th><th>source</th></tr>" + "".join(rows) + "</table>"
        f'<p class="method">{html.escape(calibration.method)}</p>'
    )


_STYLE = """
body { font-family: system-ui, sans-serif; margin: 2em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 2em; }
.view { display: flex; gap: 0.5em; margin-bottom: 1em; }
figure { margin: 0; } figure img { width: 100%; max-width: 380px; image-rendering: pixelated; }
figcaption { font-size: 0.8em; color: #555; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border-bottom: 1px solid #ddd; padding: 0.2em 0.8em; text-align: left; }
td.assumed { color: #a40; } .method { font-size: 0.8em; color: #555; }
pre { background: #f6f6f6; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
.figures img { max-width: 560px; }
"""

_SCRIPT = """
const slider = document.getElementById("exposure");
function show(index) {
  slider.value = index;
  document.getElementById("exposure-label").textContent = EXPOSURES[index] + " s";
  document.querySelectorAll("img.ldr").forEach((image) => {
    image.src = LDR[Number(image.dataset.view)][index];
    image.dataset.exposure = EXPOSURES[index];
  });
  document.body.dataset.exposure = EXPOSURES[index];
}
slider.addEventListener("input", () => show(Number(slider.value)));
window.addEventListener("load", () => {
  const images = [...document.images];
  const loaded = images.filter((image) => image.complete && image.naturalWidth > 0);
  document.body.dataset.imagesLoaded = loaded.length;
  document.body.dataset.imagesTotal = images.length;
  const asked = /exposure=(\\d+)/.exec(location.hash);
  show(asked ? Math.min(Number(asked[1]), EXPOSURES.length - 1) : Number(slider.value));
});
"""


def _figure(uri: str | None, caption: str, extra: str = "") -> str:
    if uri is None:
        return f"<figure><figcaption>{html.escape(caption)}: not written</figcaption></figure>"
    return (
        f'<figure><img {extra} src="{uri}" alt="{html.escape(caption)}">'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _page(*, title, metrics, saved, views, exposures, reference_what, figures, calibration) -> str:
    middle = len(exposures) // 2
    view_rows = []
    for index, view in enumerate(views):
        ldr = view["ldr"][middle] if view["ldr"] else None
        view_rows.append(
            '<div class="view">'
            + _figure(view["reference"], f"view {view['name']}: {reference_what}")
            + _figure(ldr, "render at the slider's exposure", f'class="ldr" data-view="{index}"')
            + _figure(view["hdr"], "HDR render, tone-mapped")
            + "</div>"
        )
    scores = format_scores(metrics) if metrics else "no scores: the fit wrote no metrics.json"
    software = saved.get("software", {})
    config = saved.get("config", {})
    return "".join(
        [
            '<!doctype html><html lang="en"><head><meta charset="utf-8">',
            f"<title>seecap: {html.escape(title)}</title><style>{_STYLE}</style></head><body>",
            f"<h1>seecap fit: {html.escape(title)}</h1>",
            "<h2>Scores</h2><pre>" + html.escape(scores) + "</pre>",
            "<h2>Views</h2>",
            '<p>Exposure <input type="range" id="exposure" min="0" '
            f'max="{max(len(exposures) - 1, 0)}" value="{middle}"> '
            '<span id="exposure-label"></span></p>',
            "".join(view_rows),
            '<h2>Training, responses, camera path</h2><div class="figures">',
            "".join(_figure(uri, name) for name, uri in figures.items()),
            "</div><h2>Sensor calibration</h2>",
            _calibration_rows(calibration),
            "<h2>Configuration and software</h2><pre>",
            html.escape(json.dumps({"software": software, "config": config}, indent=1)),
            "</pre><script>",
            f"const EXPOSURES = {json.dumps(exposures)};",
            f"const LDR = {json.dumps([view['ldr'] for view in views])};",
            _SCRIPT,
            "</script></body></html>",
        ]
    )
