"""Settings, database and ASGI middleware of the service."""
