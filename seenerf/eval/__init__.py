"""A fitted model judged: its views rendered and written, metrics, scores, registration, the CRF."""
