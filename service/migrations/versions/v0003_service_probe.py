"""The health probe's table (issue 44): one row per probe name that ``GET /health`` rewrites.

A database that already has it (made by ``create_all`` of a version between issue 44 and Alembic)
keeps it.

Revision ID: v0003
Revises: v0002
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "v0003"
down_revision = "v0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    if not sa.inspect(op.get_bind()).has_table("service_probe"):
        op.create_table("service_probe",
                        sa.Column("name", sa.String(32), primary_key=True),
                        sa.Column("written_at", sa.DateTime(), nullable=False))


def downgrade() -> None:
    op.drop_table("service_probe")
