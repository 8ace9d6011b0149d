"""CLI command that starts the HTTP service (``rotordiag serve``)."""
from __future__ import annotations

import typer


def register(app: typer.Typer) -> None:
    """Add ``rotordiag serve`` to the ``rotordiag`` app."""

    @app.command()
    def serve(
        host: str = typer.Option("127.0.0.1", help="Interface to listen on (0.0.0.0 for every interface)."),
        port: int = typer.Option(8000, min=1, max=65535, help="TCP port."),
    ) -> None:
        """Serve the HTTP API (settings from ROTORDIAG_* environment variables or .env; see docs/service.md)."""
        import os

        # Requests already run in parallel (one diagnosis per CPU); OpenMP/BLAS threads inside each
        # would oversubscribe the cores. Set before the app (scikit-learn, NumPy) is imported.
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            os.environ.setdefault(var, "1")
        import uvicorn
        from pydantic import ValidationError

        from rotordiag.service.core.config import Settings

        try:
            settings = Settings()
        except ValidationError as exc:
            msgs = "; ".join(str(e.get("msg", "")).removeprefix("Value error, ") for e in exc.errors())
            typer.secho(f"error: invalid settings: {msgs}", fg="red", err=True)
            raise typer.Exit(2) from None
        try:
            # One server process: it owns the job table (a second uvicorn worker would mark the first
            # one's running jobs interrupted at its startup). Diagnoses use every core through the
            # diagnosis worker processes (ROTORDIAG_DIAGNOSIS_WORKERS, service/pool.py); jobs scale out
            # on Dask.
            uvicorn.run("rotordiag.service.main:app", host=host, port=port,
                        log_level=settings.log_level.lower(), access_log=False)
        except OSError as exc:  # e.g. address in use
            typer.secho(f"error: cannot listen on {host}:{port}: {exc}", fg="red", err=True)
            raise typer.Exit(2) from None
