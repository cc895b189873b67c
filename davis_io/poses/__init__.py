"""Camera poses from event-deblurred frames: EDI, COLMAP with recovery, alignment to truth."""

from davis_io.poses.colmap import ColmapError
from davis_io.poses.estimate import PoseReport, estimate_poses

__all__ = ["ColmapError", "PoseReport", "estimate_poses"]
