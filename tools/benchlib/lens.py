"""The lens benchmark's markdown section, rendered from its JSON document alone."""

from __future__ import annotations

from benchlib.machine import measured_line

__all__ = ["LENS_CASES", "lens_report"]

LENS_CASES = {
    "pinhole": "the same scene through an undistorted lens, default fit (lens estimated)",
    "known": "distorted lens, its DV calibration file given (`--camera-calibration`)",
    "estimated": "distorted lens, default fit (COLMAP fits a radial lens)",
    "ignored": "distorted lens ignored: its intrinsics given without the distortion",
}
"""Each fit of the benchmark, by name, and what it is."""


def _lens(case: dict) -> str:
    fx = case["intrinsics"][0]
    terms = ", ".join(
        f"{name} {value:+.3f}"
        for name, value in zip(("k1", "k2", "p1", "p2"), case["distortion"], strict=False)
    )
    return f"f {fx:.1f}" + (f", {terms}" if terms else ", none")


def _row(name: str, case: dict, reference: dict | None) -> str:
    if case.get("error"):
        return f"| {name} | failed: {case['error'][:80]} | | | | | |"
    gap = "-" if reference is None else f"{case['hdr_psnr'] - reference['hdr_psnr']:+.2f}"
    return (
        f"| {name} | {_lens(case)} | {case['rotation_deg_median']:.3f} / "
        f"{case['rotation_deg_max']:.3f} | {case['hdr_psnr']:.2f} | {case['novel_psnr']:.2f} | "
        f"{gap} | {case['steps']} |"
    )


def lens_report(document: dict) -> str:
    """Markdown: the drawn lens, then each fit's lens, pose error, scores and steps."""
    cases = document["cases"]
    reference = cases.get("pinhole")
    reference = None if reference is None or reference.get("error") else reference
    truth = document["true_lens"]
    lines = [
        measured_line(document),
        "",
        f"Scene `{document['scene']}`, seed {document['seed']}, {document['frames']} frames; "
        f"each fit `{document['fit']}`, two side by side. The distorted lens was drawn by "
        f"`--lens random`: f {truth['fx']:.1f} px, "
        + ", ".join(f"{key} {truth[key]:+.4f}" for key in ("k1", "k2", "p1", "p2") if key in truth)
        + ". Pose errors after a similarity alignment to the true cameras; HDR gap against the "
        "undistorted session.",
        "",
        "| fit | lens the poses used | rotation error median / max (deg) | HDR dB | novel dB | "
        "HDR - pinhole's dB | steps |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += [_row(name, cases[name], reference) for name in LENS_CASES if name in cases]
    lines += [""] + [f"* **{name}**: {text}." for name, text in LENS_CASES.items()]
    return "\n".join(lines)
