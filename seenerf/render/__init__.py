"""Rays, where the field is sampled along them, volume rendering, and the renderer composing it."""
