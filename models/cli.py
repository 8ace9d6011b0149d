"""CLI commands of the models package (train, models, diagnose)."""
from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add this package's commands to the ``rotordiag`` app (filled by the models work)."""
