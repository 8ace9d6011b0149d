"""The ``rotordiag`` command line: one Typer app, each package adds its commands.

Every package that contributes commands exposes ``register(app)`` in its own
``cli`` module; heavy imports happen inside the commands so ``rotordiag --help``
stays fast.
"""
from __future__ import annotations

import typer

app = typer.Typer(
    name="rotordiag",
    help="Generator-exciter coupling misalignment: simulate, build datasets, train, diagnose, serve.",
    no_args_is_help=True,
    add_completion=False,
)


def _register_all() -> None:
    from rotordiag.models import cli as models_cli
    from rotordiag.models import transient_cli
    from rotordiag.service import cli as service_cli
    from rotordiag.simulator import cli as simulator_cli
    from rotordiag.simulator.analysis import cli as analysis_cli
    from rotordiag.simulator.dataset import cli as dataset_cli
    from rotordiag.simulator.steady import cli as steady_cli

    for module in (simulator_cli, analysis_cli, dataset_cli, steady_cli, models_cli, transient_cli, service_cli):
        module.register(app)


_register_all()


def main() -> None:
    """Console-script entry point."""
    app()
