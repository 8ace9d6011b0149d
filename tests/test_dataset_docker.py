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


API = ("api-1", "api-2")


def test_compose_has_db_two_api_replicas_lb_scheduler_and_workers(compose):
    services = compose["services"]
    assert set(services) == {"db", "api-1", "api-2", "lb", "scheduler", "worker"}
    ours = {name: s for name, s in services.items() if name not in ("db", "lb")}
    assert {s["image"] for s in ours.values()} == {"rotordiag:latest"}
    assert services["api-1"]["build"] == "."
    assert services["db"]["image"].startswith("postgres:") and services["lb"]["image"].startswith("nginx:")
    assert (REPO / "Dockerfile").is_file()
    # shared data volume (registry, datasets) and the database's own, declared at top level
    assert {"data", "pgdata"} <= set(compose["volumes"])
    for name in (*API, "worker"):
        assert "data:/data" in services[name]["volumes"], name
    assert "tcp://scheduler:8786" in services["worker"]["command"]
    assert services["worker"]["deploy"]["replicas"] >= 1


def test_api_replicas_share_postgresql_and_have_their_own_names(compose):
    from rotordiag.service.core.config import Settings

    services = compose["services"]
    db = services["db"]["environment"]
    names = set()
    for name in API:
        env = services[name]["environment"]
        url = env["ROTORDIAG_DATABASE_URL"]
        assert url.startswith("postgresql://") and "@db:5432/" in url
        assert url.endswith("/" + db["POSTGRES_DB"]) and url.startswith(f"postgresql://{db['POSTGRES_USER']}:")
        assert env["ROTORDIAG_DASK_SCHEDULER_ADDRESS"] == "tcp://scheduler:8786"
        assert env["ROTORDIAG_ENVIRONMENT"] == "production" and "ROTORDIAG_API_KEY" in env
        for key in env:       # every ROTORDIAG_ variable is a setting the service reads
            if key.startswith("ROTORDIAG_"):
                assert key.removeprefix("ROTORDIAG_").lower() in Settings.model_fields, key
        names.add(env["ROTORDIAG_REPLICA_ID"])
        assert services[name]["depends_on"]["db"]["condition"] == "service_healthy"
        assert services[name]["stop_grace_period"] == "45s"     # docs/service.md, "Stopping the server"
    assert names == set(API)


def test_every_service_has_a_healthcheck_and_waits_for_healthy_dependencies(compose):
    from rotordiag.service.api.routes.health import router

    services = compose["services"]
    for name, svc in services.items():
        test = svc["healthcheck"]["test"]
        assert test[0] == "CMD", name
        if test[1] == "python":
            compile(test[3], f"<healthcheck of {name}>", "exec")   # valid Python
        for dep in (svc.get("depends_on") or {}).values():
            assert dep["condition"] == "service_healthy", name
    for name in API:
        assert "http://127.0.0.1:8000/health" in services[name]["healthcheck"]["test"][3]
        assert "8000" in services[name]["command"]
    assert "/health" in {r.path for r in router.routes}
    assert services["db"]["healthcheck"]["test"][1] == "pg_isready"
    assert ":8787" in services["scheduler"]["command"] and "8787/health" in services["scheduler"]["healthcheck"]["test"][3]


def test_lb_config_sends_to_both_replicas_and_never_resends_a_sent_post(compose):
    lb = compose["services"]["lb"]
    mount = next(v for v in lb["volumes"] if v.endswith(":/etc/nginx/conf.d/default.conf:ro"))
    conf = (REPO / mount.split(":")[0]).read_text()
    upstream = re.search(r"upstream rotordiag_api \{(.*?)\}", conf, re.S).group(1)
    assert re.findall(r"server (api-\d):8000", upstream) == list(API)
    assert "proxy_pass http://rotordiag_api;" in conf
    assert "non_idempotent" not in conf          # a POST /diagnose that reached a replica is not sent again
    assert "/lb-health" in conf and "/lb-health" in lb["healthcheck"]["test"][-1]
    body = re.search(r"client_max_body_size (\d+)m;", conf)
    from rotordiag.service.core.config import Settings

    assert int(body.group(1)) * 2**20 >= Settings.model_fields["max_body_bytes"].default


def test_docker_compose_config_accepts_the_file():
    """`docker compose config` where docker (with the compose plugin) works; skipped elsewhere."""
    import os
    import shutil

    docker = shutil.which("docker")
    if docker is None or subprocess.run([docker, "compose", "version"], capture_output=True, timeout=30).returncode:
        pytest.skip("docker compose is not installed here")
    env = dict(os.environ, ROTORDIAG_API_KEY="k", POSTGRES_PASSWORD="p")
    run = subprocess.run([docker, "compose", "-f", str(REPO / "docker-compose.yml"), "config", "--quiet"],
                         capture_output=True, text=True, timeout=60, env=env)
    assert run.returncode == 0, run.stderr


def _console_scripts() -> set[str]:
    return {ep.name for ep in entry_points(group="console_scripts")}


@pytest.mark.parametrize("service", ["api-1", "api-2", "scheduler", "worker"])
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
