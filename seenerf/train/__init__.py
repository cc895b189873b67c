"""Training a model on a session: the builder, the loop, losses, checkpoints, fits and runs."""
