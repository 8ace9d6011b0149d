"""CLI commands of the dataset package (``rotordiag dataset ...``)."""
from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add this package's commands to the ``rotordiag`` app (filled by the dataset work)."""
