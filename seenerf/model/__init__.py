"""The imaging model of a fit: its variants, presets and configuration, and the model they build."""
