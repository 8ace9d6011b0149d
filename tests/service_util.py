"""Helpers shared by the service tests (not a test module)."""
from __future__ import annotations

from pathlib import Path

API_KEY = "test-key-0123456789"


def make_settings(tmp_path: Path, **overrides):
    """Settings for an isolated app: its own data dir, database and registry under ``tmp_path``."""
    from service.core.config import Settings

    values = dict(data_dir=tmp_path / "data", api_key=API_KEY, environment="development",
                  dask_local_workers=1, _env_file=None)
    values.update(overrides)
    return Settings(**values)


def auth() -> dict[str, str]:
    return {"X-API-Key": API_KEY}
