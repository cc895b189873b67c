"""Training data: a session as arrays, their frames, random batches, sub-frames, a synthetic one."""
