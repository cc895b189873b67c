"""The quick plan run two ways, local and on Ray: one JSON document and its markdown section."""

from __future__ import annotations

import math

from benchlib.machine import measured_line

__all__ = ["ROW_FIELDS", "side_by_side_report"]

ROW_FIELDS = ("session", "preset", "variant", "budget_s", "seed", "status", "steps")
"""What each run keeps of a rung besides its scores (``hdr_psnr``, ``novel_psnr``)."""


def _rung(row: dict) -> str:
    seed = f" seed {row['seed']}" if row.get("seed") else ""
    return f"{row['session']} {row['preset']} {row['variant']}{seed} {row['budget_s']:g} s"


def _cell(row: dict | None) -> str:
    if row is None:
        return "not run"
    if row["status"] != "ok":
        return row["status"][:60]
    return f"{row['hdr_psnr']:.2f} / {row['novel_psnr']:.2f} / {row['steps']}"


def _difference(local: dict | None, ray: dict | None) -> str:
    if not local or not ray or local["status"] != "ok" or ray["status"] != "ok":
        return "-"
    hdr, novel = (ray[key] - local[key] for key in ("hdr_psnr", "novel_psnr"))
    return f"{hdr:+.2f} / {novel:+.2f}"


def side_by_side_report(document: dict) -> str:
    """Markdown: wall times and their ratio, then every rung's scores both ways."""
    local, ray = document["runs"]["local"], document["runs"]["ray"]
    ratio = ray["wall_s"] / local["wall_s"] if local["wall_s"] else math.nan
    by_rung = {}
    for name, run in (("local", local), ("ray", ray)):
        for row in run["rows"]:
            by_rung.setdefault(_rung(row), {})[name] = row
    ok = {
        name: sum(r["status"] == "ok" for r in run["rows"])
        for name, run in document["runs"].items()
    }
    differences = [
        abs(rows["ray"][measure] - rows["local"][measure])
        for rows in by_rung.values()
        if rows.get("local", {}).get("status") == "ok" and rows.get("ray", {}).get("status") == "ok"
        for measure in ("hdr_psnr", "novel_psnr")
    ]
    lines = [
        measured_line(document),
        "",
        f"The quick plan with {document['ray_cpus_per_fit']} core per fit: one rung after "
        f"another (`{local['command']}`), then each rung a Ray task on a local instance "
        f"(`{ray['command']}`), the ladders side by side.",
        "",
        "| | local | Ray, local instance |",
        "|---|---|---|",
        f"| wall time | {local['wall_s'] / 60:.1f} min | {ray['wall_s'] / 60:.1f} min "
        f"({ratio:.2f}x) |",
        f"| rungs scored | {ok['local']} / {len(local['rows'])} | "
        f"{ok['ray']} / {len(ray['rows'])} |",
        "",
        "| rung | local HDR / novel dB / steps | Ray HDR / novel dB / steps | Ray - local dB |",
        "|---|---|---|---|",
    ]
    for rung, rows in by_rung.items():
        lines.append(
            f"| {rung} | {_cell(rows.get('local'))} | {_cell(rows.get('ray'))} | "
            f"{_difference(rows.get('local'), rows.get('ray'))} |"
        )
    if differences:
        lines += [
            "",
            f"Largest difference of a score: {max(differences):.2f} dB; mean "
            f"{sum(differences) / len(differences):.2f} dB over {len(differences)} scores.",
        ]
    return "\n".join(lines)
