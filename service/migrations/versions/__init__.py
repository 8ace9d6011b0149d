"""Schema versions, oldest first: ``v0001`` the schema before Alembic, ``v0002`` job leases, ``v0003`` the
health probe table, ``v0004`` the asset's probe configuration."""
