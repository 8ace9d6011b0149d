"""Schema versions, oldest first: ``v0001`` the schema as of issue 47's start, ``v0002`` job leases."""
