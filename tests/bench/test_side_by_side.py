from benchlib.side_by_side import side_by_side_report


def row(variant, budget, hdr, novel, steps, status="ok"):
    return {
        "session": "room",
        "preset": "fast",
        "variant": variant,
        "budget_s": budget,
        "seed": 0,
        "status": status,
        "steps": steps,
        "hdr_psnr": hdr,
        "novel_psnr": novel,
    }


def test_wall_times_ratio_and_every_rung_side_by_side():
    document = {
        "commit": "abc1234",
        "machine": "2 cores",
        "command": "tools/bench_cluster.py",
        "ray_cpus_per_fit": 1,
        "runs": {
            "local": {
                "command": "tools/bench.py --quick",
                "wall_s": 900.0,
                "rows": [row("full", 20, 24.0, 22.5, 300), row("full", 60, 27.0, 25.0, 900)],
            },
            "ray": {
                "command": "tools/bench.py --quick --ray local",
                "wall_s": 540.0,
                "rows": [
                    row("full", 20, 23.5, 22.75, 210),
                    row("full", 60, 0.0, 0.0, 0, status="failed (exit 1): boom"),
                ],
            },
        },
    }
    text = side_by_side_report(document)
    assert "| wall time | 15.0 min | 9.0 min (0.60x) |" in text
    assert "| rungs scored | 2 / 2 | 1 / 2 |" in text
    assert (
        "| room fast full 20 s | 24.00 / 22.50 / 300 | 23.50 / 22.75 / 210 | -0.50 / +0.25 |"
        in text
    )
    assert "| room fast full 60 s | 27.00 / 25.00 / 900 | failed (exit 1): boom | - |" in text
    assert "Largest difference of a score: 0.50 dB; mean 0.38 dB over 2 scores." in text
