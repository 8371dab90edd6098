"""Tables built from the JSON results the demos and benchmarks commit."""

from __future__ import annotations


def setup(app) -> None:
    """Register the table directives."""
