"""Where a pixel has fired what it owes: the time points at which its event count is whole.

A DVS pixel fires at most once per dead time (its refractory period). One swept by a change
larger than that rate allows fires at the limit and owes the rest, so the events counted
between two time points fall short of the change between them whenever the pixel was still
paying at either point. Such a pixel's events follow each other at about the dead time: where
the two events on either side of a time point are that close, the pixel was firing as fast as
it can there. Between two points where it was not, it had caught up at both ends, so its count
holds the whole change in between, however fast the light moved in the meantime.
"""

from __future__ import annotations

import numpy as np

from davis_io.pixel_trains import pixel_trains

__all__ = ["SLEWING_INTERVALS", "settled_points"]

SLEWING_INTERVALS = 2.0
"""Events on either side of a time point closer than this many dead times: the pixel was firing
at its limit there (a limited pixel's intervals spread around one dead time)."""


def settled_points(
    events: np.ndarray, times_us: np.ndarray, width: int, height: int, dead_time_us: float
) -> np.ndarray:
    """Whether each pixel had fired all it owed at each time point.

    Args:
        events: ``EVENT_DTYPE`` events sorted by time, reaching at least
            ``SLEWING_INTERVALS * dead_time_us`` beyond the first and last point.
        times_us: ``(P,)`` time points, µs.
        width: sensor width.
        height: sensor height.
        dead_time_us: the pixels' dead time; 0 (none measured): every point is settled.

    Returns:
        ``(P, height, width)`` bool, False where the pixel's last event at or before the point
        and its first event after it are at most ``SLEWING_INTERVALS * dead_time_us`` apart.
    """
    settled = np.ones((len(times_us), height * width), bool)
    if dead_time_us <= 0 or len(events) < 2:
        return settled.reshape(len(times_us), height, width)
    trains = pixel_trains(
        events["y"].astype(np.int64) * width + events["x"],
        events["t"].astype(np.int64),
        height * width,
    )
    last = len(trains.time_us) - 1
    for index, point in enumerate(np.asarray(times_us, np.int64)):
        near = trains.around(float(point))
        gap = trains.time_us[np.minimum(near.after, last)] - trains.time_us[near.before]
        limited = near.has_before & near.has_after & (gap <= SLEWING_INTERVALS * dead_time_us)
        settled[index] = ~limited
    return settled.reshape(len(times_us), height, width)
