# AMRA dashboard image: `docker build -t amra . && docker run -p 5006:5006 amra`,
# then open http://localhost:5006/main
ARG BASE=python:3.11-slim
FROM ${BASE}

ENV PYTHONUNBUFFERED=1 \
    NUMBA_CACHE_DIR=/tmp/numba-cache \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PIP_ROOT_USER_ACTION=ignore

# libgomp1: Numba's OpenMP threading layer links the system libgomp.so.1.
RUN apt-get update \
    && apt-get install -y --no-install-recommends libgomp1 \
    && rm -rf /var/lib/apt/lists/*

RUN useradd --create-home --uid 1000 amra

WORKDIR /opt/amra

# Dependencies first (cached layer), read from pyproject.toml.
COPY pyproject.toml README.md ./
RUN python3 -c "import tomllib; print('\n'.join(tomllib.load(open('pyproject.toml', 'rb'))['project']['dependencies']))" > /tmp/requirements.txt \
    && python3 -m pip install --no-cache-dir -r /tmp/requirements.txt \
    && rm /tmp/requirements.txt

# The project itself, editable: the solver finds assets/ relative to the repo copy.
COPY . .
RUN python3 -m pip install --no-cache-dir --no-deps -e .

USER amra
EXPOSE 5006

HEALTHCHECK --interval=30s --timeout=10s --start-period=60s --retries=3 \
    CMD python3 -c "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:5006/liveness', timeout=5).status != 200)"

# '*' accepts any websocket origin; behind a known host name set
# AMRA_WEBSOCKET_ORIGIN=host[:port] instead.
CMD ["sh", "-c", "exec panel serve app/main.py --address 0.0.0.0 --port 5006 --allow-websocket-origin \"${AMRA_WEBSOCKET_ORIGIN:-*}\" --num-threads 0 --liveness"]
