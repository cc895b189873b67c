"""``seecap fit FOLDER [options]`` of a tiny analytic scene (preparation skipped), in a process of
its own; prints ``ray imported: True|False`` after the fit."""

import sys

import seenerf.cli.sessions
import seenerf.train.session_fit
from davis_io.cli import main
from seenerf.data.synthetic import plane_scene

if __name__ == "__main__":
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    seenerf.cli.sessions.read_manifest = lambda session: None
    seenerf.cli.sessions.prepare_session = lambda session, b, log, camera_calibration, threads: 0.0
    seenerf.cli.sessions.session_bins = lambda session, config: 2
    seenerf.train.session_fit.session_bins = seenerf.cli.sessions.session_bins
    seenerf.train.session_fit.training_data = lambda *args, **kwargs: scene
    arguments = ["fit", *sys.argv[1:], "--steps", "3", "--batch-pixels", "6", "--warm-steps", "2"]
    status = main([*arguments, "--validation-share", "0.1", "--quiet"])
    print(f"ray imported: {'ray' in sys.modules}")
    sys.exit(status)
