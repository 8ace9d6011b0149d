"""CLI command that starts the HTTP service (``rotordiag serve``)."""
from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add this package's commands to the ``rotordiag`` app (filled by the service work)."""
