"""``seecap fit FOLDER`` of a tiny analytic scene (preparation skipped), for a disk that fills."""

import sys

import davis_io.prepare
import seenerf.train
import seenerf.train.fit
from davis_io.cli import main
from seenerf.data.synthetic import plane_scene

if __name__ == "__main__":
    scene = plane_scene(height=8, width=10, frames=3, b=2, test_views=1)
    davis_io.prepare.prepare_session = lambda session, b, log=print: 0.0
    seenerf.train.fit.session_bins = lambda session, config: 2
    seenerf.train.fit.load_training_data = lambda *args, **kwargs: scene
    arguments = ["fit", sys.argv[1], "--steps", "3", "--batch-pixels", "6", "--warm-steps", "2"]
    sys.exit(main([*arguments, "--validation-share", "0.1", "--quiet"]))
