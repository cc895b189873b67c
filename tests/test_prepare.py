"""The preparation's progress lines, on a clock the test turns."""

from davis_io.prepare import StageLines


def test_stage_lines_say_each_stage_and_each_quarter_with_the_time_left():
    lines, now = [], [0.0]
    progress = StageLines(lines.append, clock=lambda: now[0])
    progress("features", 0, 0)
    for done in range(1, 9):
        now[0] = 2.0 * done  # two seconds per image
        progress("registering", done, 8)
    progress("matching", 0, 0)
    assert lines == [
        "poses: features",
        "poses: registering",
        "poses: registering 2/8 in 2 s, about 6 s left",
        "poses: registering 4/8 in 6 s, about 6 s left",
        "poses: registering 6/8 in 10 s, about 3 s left",
        "poses: registering 8/8 in 14 s, about 0 s left",
        "poses: matching",
    ]
