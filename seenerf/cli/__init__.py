"""``seecap`` verbs of the trainer: fit, render, eval (torch is imported only when they run)."""

__all__: list[str] = []
