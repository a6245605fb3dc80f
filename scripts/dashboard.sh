#!/usr/bin/env bash
# Quick start, command 1: create/reuse the project virtual environment .venv, install AMRA into it
# and serve the dashboard (`amra serve`). AMRA_ADDRESS / AMRA_PORT change where it listens; extra
# arguments go to `amra serve` (see `amra serve --help`).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/venv.sh
amra_venv ""
exec "$PY" -m amra_core.cli serve --address "${AMRA_ADDRESS:-127.0.0.1}" --port "${AMRA_PORT:-5006}" "$@"
