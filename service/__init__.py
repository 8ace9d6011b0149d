"""rotordiag HTTP service: FastAPI app ``service.main:app``, started by ``rotordiag serve``.

Layout (FastAPI full-stack template): ``main.py`` builds the app; ``api/routes/*``
one router per resource; ``api/deps.py`` typed dependencies; ``core/config.py``
the settings; ``core/db.py`` the tables; ``core/limits.py`` the body-size
middleware; ``schemas.py`` request/response models; ``jobs.py`` and ``work.py``
the job manager and what jobs do; ``inference.py`` the model store.
See ``docs/service.md``.
"""
