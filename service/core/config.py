"""Service settings: one pydantic-settings class read from ``ROTORDIAG_*`` env vars and ``.env``.

Every setting has an embedded default so ``rotordiag serve`` works on a fresh
clone (development mode, SQLite file and model registry under ``./data``, a
local Dask cluster created the first time a job runs). Production mode refuses
the unsafe defaults (an empty API key).
"""
from __future__ import annotations

import logging
import secrets
from functools import cached_property
from pathlib import Path
from typing import Literal

from pydantic import Field, SecretStr, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from rotordiag.models.registry import shipped_registry_dir

log = logging.getLogger("rotordiag.service")

#: The registry shipped in the repository (default model, trained by the project's own pipeline).
SHIPPED_REGISTRY_DIR = shipped_registry_dir()


class Settings(BaseSettings):
    """Settings of the rotordiag HTTP service.

    Each field is read from the environment variable ``ROTORDIAG_<FIELD>``
    (case-insensitive) or from a ``.env`` file in the working directory.
    """

    model_config = SettingsConfigDict(
        env_prefix="ROTORDIAG_", env_file=".env", env_file_encoding="utf-8", extra="ignore",
    )

    environment: Literal["development", "production"] = Field(
        "development",
        description="`development` generates a random API key when none is set and logs it once; "
        "`production` refuses to start without an API key.",
    )
    data_dir: Path = Field(Path("./data"), description="Directory for the database, datasets and retrained models.")
    database_url: str = Field(
        "", description="SQLAlchemy URL of the store: empty means a SQLite file `<data_dir>/rotordiag.sqlite3` "
        "(one server process); `postgresql://user:password@host:5432/rotordiag` is the production store that "
        "several API replicas share (docs/service.md).",
    )
    api_key: SecretStr = Field(
        SecretStr(""),
        description="Key required in the `X-API-Key` header by every write endpoint except /diagnose.",
    )
    diagnose_requires_key: bool = Field(
        False, description="Also require the API key on POST /diagnose and /diagnose/batch; off by default so "
        "monitoring systems can diagnose without a key (an anonymous diagnosis is answered, never stored in an "
        "asset's history: storing it needs the key).")
    dask_scheduler_address: str = Field(
        "", description="Address of an existing Dask scheduler (e.g. `tcp://scheduler:8786`); "
        "empty means a local cluster created the first time a job runs.",
    )
    dask_local_workers: int = Field(2, ge=1, le=256, description="Worker processes of the local Dask cluster.")
    max_body_bytes: int = Field(
        64 * 1024 * 1024, ge=1024,
        description="Largest request body accepted, in bytes, counted while it streams in (413 above it).",
    )
    model_registry_dir: Path | None = Field(
        None,
        description="Model registry the service diagnoses with and registers retrained models into. "
        "Empty means `<data_dir>/registry`, seeded on first start with the shipped default registry.",
    )
    shipped_registry_dir: Path = Field(
        SHIPPED_REGISTRY_DIR,
        description="Read-only registry copied into an empty `model_registry_dir` on first start "
        "(default: the repository's `models/default_registry/`).",
    )
    max_batch_records: int = Field(64, ge=1, le=10_000, description="Largest number of records in POST /diagnose/batch.")
    diagnosis_threads: int = Field(
        0, ge=0, le=256, description="Diagnoses computed at the same time; 0 means one per CPU available.")
    diagnosis_workers: int = Field(
        -1, ge=-1, le=256,
        description="Worker processes that compute diagnoses (parse, features, verdict) so that requests use "
        "every core; -1 means one per CPU available, 0 computes them in the server process's threads "
        "(`diagnosis_threads`).")
    diagnosis_worker_memory_mb: int = Field(
        1024, ge=0, le=1_048_576,
        description="Memory, MiB, each diagnosis worker may allocate beyond its size once it has loaded the model "
        "(its RLIMIT_AS is set to that sum); a request that needs more is answered 422. 0: no limit.")
    diagnosis_timeout_s: float = Field(
        60.0, gt=0, le=3600, allow_inf_nan=False,
        description="Worker time one diagnosis (or /ui/plot-data request) may take, s; past it the worker is killed "
        "and replaced and the request answered 422 (not retried).")
    body_timeout_s: float = Field(
        60.0, gt=0, le=3600, allow_inf_nan=False,
        description="Time a client has to send a request body once its headers have arrived, s; a slower one "
        "is answered 408 and its connection closed.")
    job_threads: int = Field(1, ge=1, le=16, description="Jobs run at the same time (each fans out on Dask).")
    replica_id: str = Field(
        "", max_length=100, description="This API process's name among the replicas sharing the database (in "
        "job leases, /health and /metrics); empty means `<hostname>-<pid>-<random>`, new at each start.")
    job_lease_s: float = Field(
        30.0, ge=1.0, le=3600, allow_inf_nan=False,
        description="How long a replica's hold on a running job lasts without renewal, s (renewed every third of "
        "it); a job whose holder died is taken over by another replica at most this plus `job_poll_s` later.")
    job_poll_s: float = Field(
        1.0, gt=0, le=60, allow_inf_nan=False,
        description="How often each replica looks for queued jobs and expired leases, s.")
    shutdown_timeout_s: float = Field(
        10.0, ge=0, le=600, allow_inf_nan=False,
        description="At SIGINT/SIGTERM, how long the server waits for running jobs to stop, s; a job still running "
        "then is left `interrupted` (resumable) and the process exits anyway.")
    min_free_disk_mb: int = Field(
        1024, ge=0, le=2**40,
        description="Free space, MiB, below which the disk holding `data_dir` counts as nearly full: /health says "
        "`degraded`. 0: not checked.")
    history_keep_recordings: int = Field(
        1000, ge=0, le=10_000_000,
        description="Full diagnoses (verdict, key features, signature) kept per asset, the latest first; older "
        "ones keep only their summary (time, severity, Δ and interval, speed, alarm, change). 0: no count limit.")
    history_keep_days: float = Field(
        90.0, ge=0, le=36_500, allow_inf_nan=False,
        description="Days a full diagnosis is kept before only its summary is; 0: no age limit.")
    history_max_rows: int = Field(
        100_000, ge=0, le=100_000_000,
        description="Stored diagnoses per asset, full or summary; the oldest beyond it are deleted. 0: no limit.")
    history_summary_days: float = Field(
        3650.0, ge=0, le=36_500, allow_inf_nan=False,
        description="Days a diagnosis summary is kept before it is deleted; 0: kept for ever.")
    webhook_max_pending: int = Field(
        1000, ge=1, le=1_000_000,
        description="Webhook deliveries waiting to be sent, all webhooks together; an event beyond it is stored "
        "as `dropped` (the diagnosis is never held up or refused for it).")
    webhook_max_attempts: int = Field(
        6, ge=1, le=100, description="Tries of one webhook delivery before it is marked `failed`.")
    webhook_backoff_s: float = Field(
        2.0, gt=0, le=3600, allow_inf_nan=False,
        description="Wait before the second try of a webhook delivery; doubled for each further try (at most 1 h).")
    webhook_timeout_s: float = Field(
        10.0, gt=0, le=300, allow_inf_nan=False, description="Time one webhook POST may take.")
    log_level: str = Field("info", description="Log level of the service and uvicorn.")

    @field_validator("database_url", "dask_scheduler_address")
    @classmethod
    def _strip(cls, value: str) -> str:
        return value.strip()

    @model_validator(mode="after")
    def _refuse_unsafe_defaults(self) -> Settings:
        if self.environment == "production" and not self.api_key.get_secret_value().strip():
            raise ValueError(
                "ROTORDIAG_API_KEY is empty: production mode needs an API key for the write endpoints; "
                "set ROTORDIAG_API_KEY (e.g. `python -c 'import secrets; print(secrets.token_urlsafe(32))'`) "
                "or run with ROTORDIAG_ENVIRONMENT=development."
            )
        return self

    # -- derived values ---------------------------------------------------------------------
    @cached_property
    def effective_api_key(self) -> str:
        """The key write endpoints compare against (generated once per process in development)."""
        key = self.api_key.get_secret_value().strip()
        if key:
            return key
        key = secrets.token_urlsafe(24)
        log.warning(
            "ROTORDIAG_API_KEY is not set (development mode): generated the key %s for this run; "
            "send it as the X-API-Key header to write endpoints.", key,
        )
        return key

    @cached_property
    def effective_replica_id(self) -> str:
        """``replica_id``, or a name unique to this process (host, pid and a random part)."""
        import os
        import socket

        return self.replica_id.strip() or f"{socket.gethostname()}-{os.getpid()}-{secrets.token_hex(3)}"

    @property
    def effective_database_url(self) -> str:
        """The database URL, defaulting to a SQLite file under ``data_dir``."""
        if self.database_url:
            return self.database_url
        return f"sqlite:///{(self.data_dir / 'rotordiag.sqlite3').resolve()}"

    @property
    def effective_diagnosis_workers(self) -> int:
        """``diagnosis_workers``, with -1 resolved to the number of CPUs this process may use."""
        return _n_cpus() if self.diagnosis_workers < 0 else self.diagnosis_workers

    @property
    def effective_diagnosis_threads(self) -> int:
        """``diagnosis_threads``, or the number of CPUs this process may use."""
        return self.diagnosis_threads or _n_cpus()

    @property
    def registry_dir(self) -> Path:
        """The registry directory the service reads and writes."""
        return self.model_registry_dir if self.model_registry_dir is not None else self.data_dir / "registry"

    @property
    def datasets_dir(self) -> Path:
        """Where dataset jobs write their HDF5 files."""
        return self.data_dir / "datasets"


def get_settings() -> Settings:
    """Read settings from the environment (a fresh object each call; the app keeps its own)."""
    return Settings()


def _n_cpus() -> int:
    """CPUs this process may run on."""
    import os

    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)
