"""Alembic environment: runs on the connection :func:`rotordiag.service.core.db.migrate` passes in
``config.attributes["connection"]`` (online mode only; the service never writes SQL scripts)."""
from __future__ import annotations

from alembic import context

from rotordiag.service.core.db import Base

connection = context.config.attributes.get("connection")
if connection is None:  # pragma: no cover - only reachable from a bare `alembic` command line
    raise RuntimeError("run migrations through `rotordiag db upgrade` (rotordiag.service.core.db.migrate)")
context.configure(connection=connection, target_metadata=Base.metadata,
                  render_as_batch=connection.dialect.name == "sqlite")   # SQLite alters tables by copying
with context.begin_transaction():
    context.run_migrations()
