# One image for every docker-compose service: the API (`rotordiag serve`), the Dask
# scheduler (`dask scheduler`) and the Dask workers (`dask worker`). Workers run the
# same code as the client that submits dataset samples, so build the image from the
# checkout you generate datasets with (`rotordiag dataset generate --scheduler ...`).
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    # numba caches compiled kernels next to the sources by default; the install is read-only for the app user
    NUMBA_CACHE_DIR=/tmp/numba-cache \
    ROTORDIAG_DATA_DIR=/data

WORKDIR /app
COPY pyproject.toml README.md ./
COPY rotordiag ./rotordiag
COPY simulator ./simulator
COPY features ./features
COPY models ./models
COPY service ./service
RUN pip install . \
    && useradd --create-home --uid 1000 rotordiag \
    && mkdir -p /data \
    && chown rotordiag:rotordiag /data

USER rotordiag
VOLUME ["/data"]
EXPOSE 8000 8786
CMD ["rotordiag", "serve", "--host", "0.0.0.0", "--port", "8000"]
