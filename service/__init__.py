"""rotordiag HTTP service: FastAPI app ``service.main:app``, started by ``rotordiag serve``.

Layout (FastAPI full-stack template):

``main.py``            builds the app (routers, error handlers, metrics, body-size middleware)
``api/routes/*.py``    one router per resource: diagnose, jobs, models, assets, health
``api/deps.py``        typed dependencies (state, DB session, model store, job manager, API key)
``api/errors.py``      client mistakes -> 4xx with what to fix
``core/config.py``     the one ``Settings`` class (``ROTORDIAG_*`` env vars / ``.env``)
``core/db.py``         SQLAlchemy 2 tables: jobs, asset diagnoses
``core/limits.py``     ASGI middleware counting request-body bytes (413)
``schemas.py``         request/response models (units, bounds, descriptions)
``parsing.py``         JSON / NPY / CSV / HDF5 bodies -> ``features.Recording``
``inference.py``       model store: registry, cached models, one diagnosis
``store.py``           asset history rows
``jobs.py``, ``work.py``  the job manager (DB rows, threads, Dask client) and what jobs do
``metrics.py``         Prometheus: request histograms, job counts
``state.py``           what the running app holds

See ``docs/service.md``.
"""
