"""CLI commands of the nonlinear-analysis package (bifurcate, lyapunov, figures)."""
from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add this package's commands to the ``rotordiag`` app (filled by the analysis work)."""
