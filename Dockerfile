# AMRA team server: `docker build -t amra .` then
#   docker run -p 5006:5006 -v amra-data:/data amra       -> http://localhost:5006/main
# Configuration by AMRA_* environment variables (see `amra serve --help` and the README's
# Operations section). The result store lives on the volume /data.
#
# BASE: any Debian-based image with python3 >= 3.11 and its venv module. The default is the
# official slim image; the tests pass a base made locally with debootstrap (no registry here).
ARG BASE=python:3.12-slim
FROM ${BASE}

# NUMBA_CPU_NAME=generic: the Numba cache compiled below is for plain x86-64 (no AVX), so it is
# valid on every machine the image is pulled to. A host-specific cache ("host", Numba's default)
# is keyed to the build machine's CPU model and features: on any other CPU every server process
# would miss it and recompile (~7-11 CPU-s) at its first run. The cost of `generic` was measured
# on the build machine: none beyond noise (simulated s per CPU s, host vs generic: rigid 169-185
# vs 162-201, fem-coupled 51-54 vs 46-52), since the kernels are scalar loops. Build with
# `--build-arg NUMBA_CPU_NAME=host` for an image that only ever runs where it was built.
ARG NUMBA_CPU_NAME=generic
ENV PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PIP_ROOT_USER_ACTION=ignore \
    PATH=/opt/venv/bin:$PATH \
    NUMBA_CACHE_DIR=/var/cache/amra/numba \
    NUMBA_CPU_NAME=${NUMBA_CPU_NAME} \
    NUMBA_THREADING_LAYER=omp

# libgomp1: Numba's OpenMP threading layer (thread-safe, unlike the default workqueue layer).
# curl-free image: the health check uses Python's urllib.
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/*

# A venv: Debian's own python3 refuses system-wide pip installs (PEP 668); the slim image's python
# does not, but the same recipe serves both.
RUN python3 -m venv /opt/venv

# Non-root user; the only places it can write: the Numba cache and the store volume.
RUN useradd --create-home --uid 1000 --user-group amra \
    && mkdir -p /var/cache/amra/numba /data \
    && chown amra:amra /var/cache/amra/numba /data

WORKDIR /opt/amra

# Dependencies first, in their own layer, read from pyproject.toml (runtime + the dask extra) at
# the exact versions of constraints.txt (those the tests passed on): rebuilt only when either
# changes. PIP_INDEX_URL / PIP_EXTRA_INDEX_URL: optional build
# args for a package mirror (scripts/build_image.sh passes the host pip configuration's).
ARG PIP_INDEX_URL
ARG PIP_EXTRA_INDEX_URL
COPY pyproject.toml constraints.txt ./
RUN python3 -c "import tomllib; p = tomllib.load(open('pyproject.toml', 'rb'))['project']; \
print('\n'.join(p['dependencies'] + p['optional-dependencies']['dask'] + ['setuptools>=64', 'wheel']))" \
        > /tmp/requirements.txt \
    && pip install -c constraints.txt -r /tmp/requirements.txt \
    && rm /tmp/requirements.txt

# The project itself, editable (the solver finds assets/ next to the package), owned by root:
# the server cannot modify its own code.
COPY . .
RUN pip install --no-deps --no-build-isolation -e . \
    && python3 -m amra_core.cli --version

# Fill the Numba cache as the runtime user, with the runtime settings above: the first
# simulation of every server process then loads machine code instead of compiling it.
# (The warm-up also opens the map registry's store: a scratch one, removed, so nothing but the
# cache is left in the image.)
USER amra
RUN AMRA_STORE=/tmp/warm-store.sqlite python3 -m app.warmup \
    && rm -f /tmp/warm-store.sqlite* && du -sh "$NUMBA_CACHE_DIR"

ENV AMRA_ADDRESS=0.0.0.0 \
    AMRA_PORT=5006 \
    AMRA_STORE=/data/amra-store.sqlite \
    AMRA_LIVENESS=1
VOLUME /data
EXPOSE 5006

HEALTHCHECK --interval=30s --timeout=10s --start-period=60s --retries=3 \
    CMD python3 -c "import json, os, sys, urllib.request; \
u = 'http://127.0.0.1:%s%s/liveness' % (os.environ.get('AMRA_PORT', '5006'), ('/' + os.environ.get('AMRA_PREFIX', '').strip('/')).rstrip('/')); \
r = urllib.request.urlopen(u, timeout=5); sys.exit(0 if r.status == 200 and json.load(r) else 1)"

CMD ["amra", "serve"]
