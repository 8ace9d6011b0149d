"""Alembic migrations of the service database (``alembic.ini``-free: :func:`rotordiag.service.core.db.migrate`
points Alembic at this folder). One file per schema version under ``versions/``."""
