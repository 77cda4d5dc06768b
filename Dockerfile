# The service image: slim Python 3.11, dependencies from the hash-pinned lock, non-root.
#   docker build -t quickreturn-synth . && docker run -p 8000:8000 quickreturn-synth
# The base image by its tag; pin it by digest for a build that can be repeated:
#   docker build --build-arg BASE=python:3.11-slim@sha256:<digest> …
ARG BASE=python:3.11-slim
FROM ${BASE} AS base

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    OMP_NUM_THREADS=1 \
    OPENBLAS_NUM_THREADS=1 \
    SYNTH_CACHE=/opt/synth

WORKDIR /app
COPY requirements.lock .
RUN pip install --no-cache-dir --require-hashes -r requirements.lock
COPY pyproject.toml .
COPY synth synth
COPY api api
# the project itself, for its command line (quickreturn); its dependencies are the lock's
RUN pip install --no-cache-dir --no-deps --no-build-isolation .

# every compiled function a request can load, the analysis's and the motion search's, in machine
# code (synth/numerics/native.py, synth/synthesis/warm.py), built here with a C compiler so that
# the image carries the libraries and not the compiler: the service loads them as it starts
FROM base AS native
RUN apt-get update && apt-get install -y --no-install-recommends gcc libc6-dev \
    && rm -rf /var/lib/apt/lists/*
RUN python -m synth.synthesis.warm

FROM base
COPY --from=native /opt/synth /opt/synth
RUN useradd --create-home --uid 10001 app
USER app
# the port: PORT (docker run -e PORT=9000 -p 9000:9000 …), else 8000
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=3s --start-period=10s \
    CMD python -c "import os, urllib.request; urllib.request.urlopen('http://127.0.0.1:%s/health' % os.environ.get('PORT', '8000'), timeout=2)"
# one server process per core unless WEB_CONCURRENCY says otherwise; the port PORT's (api/serve.py)
CMD ["python", "-m", "api.serve", "--host", "0.0.0.0"]
