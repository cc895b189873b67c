"""See-NeRF for seecap sessions: radiance fields seen through learned sensor models (torch)."""

__all__: list[str] = []
