"""Radiance fields by name: each maps box points and view directions to density and log radiance."""

from __future__ import annotations

from seenerf.fields.factorised import VectorMatrixField, sample_vector_matrix
from seenerf.fields.mlp import PaperField, positional_encoding

__all__ = [
    "FIELDS",
    "PaperField",
    "VectorMatrixField",
    "positional_encoding",
    "sample_vector_matrix",
]

FIELDS = {
    "paper-mlp": PaperField,
    "vector-matrix": VectorMatrixField,
}
"""Field classes by name; a preset names one and passes its keyword arguments."""
