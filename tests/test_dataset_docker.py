"""docker-compose.yml and Dockerfile: what can be checked without docker."""
from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from importlib.metadata import entry_points
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent


@pytest.fixture(scope="module")
def compose():
    return yaml.safe_load((REPO / "docker-compose.yml").read_text())


def test_compose_has_api_scheduler_and_workers_from_one_image(compose):
    services = compose["services"]
    assert set(services) == {"api", "scheduler", "worker"}
    assert services["api"]["build"] == "."
    images = {s["image"] for s in services.values()}
    assert images == {"rotordiag:latest"}
    assert (REPO / "Dockerfile").is_file()
    # shared data volume, declared at top level
    assert "data" in compose["volumes"]
    assert "data:/data" in services["api"]["volumes"] and "data:/data" in services["worker"]["volumes"]
    # workers reach the scheduler by service name; the API is pointed at it too
    assert "tcp://scheduler:8786" in services["worker"]["command"]
    assert services["api"]["environment"]["ROTORDIAG_DASK_SCHEDULER_ADDRESS"] == "tcp://scheduler:8786"
    assert services["worker"]["deploy"]["replicas"] >= 1


def test_api_healthcheck_polls_the_health_endpoint(compose):
    from rotordiag.service.api.routes.health import router

    test = compose["services"]["api"]["healthcheck"]["test"]
    assert test[:3] == ["CMD", "python", "-c"]
    compile(test[3], "<healthcheck>", "exec")  # valid Python
    assert "http://127.0.0.1:8000/health" in test[3]
    assert "/health" in {r.path for r in router.routes}
    assert "8000" in compose["services"]["api"]["command"]


def _console_scripts() -> set[str]:
    return {ep.name for ep in entry_points(group="console_scripts")}


@pytest.mark.parametrize("service", ["api", "scheduler", "worker"])
def test_every_service_command_is_an_installed_entry_point_with_valid_options(compose, service):
    cmd = compose["services"][service]["command"]
    assert cmd[0] in _console_scripts(), f"{cmd[0]} is not a console script of the installed packages"
    # click parses every option given before --help: an unknown option or subcommand fails here
    run = subprocess.run([str(BIN / cmd[0]), *cmd[1:], "--help"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]


def test_rotordiag_entry_point_is_the_projects(compose):
    scripts = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["rotordiag"] == "rotordiag.cli:main"


def test_dockerfile_installs_every_package_and_has_what_pip_needs():
    text = (REPO / "Dockerfile").read_text()
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())
    packages = sorted(set(pyproject["tool"]["setuptools"]["package-dir"].values()))
    for pkg in packages:
        assert re.search(rf"^COPY {pkg} \./{pkg}$", text, re.M), f"Dockerfile does not copy {pkg}/"
    assert "COPY pyproject.toml README.md ./" in text and (REPO / "README.md").is_file()
    assert re.search(r"^RUN pip install \.", text, re.M)
    assert re.search(r'^CMD \["rotordiag", "serve"', text, re.M)
    ignored = (REPO / ".dockerignore").read_text().split()
    assert ".venv" in ignored and ".git" in ignored
