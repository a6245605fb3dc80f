#!/usr/bin/env bash
# Install AMRA (editable) and serve the dashboard at http://localhost:5006/main.
# AMRA_ADDRESS / AMRA_PORT change where it listens; extra arguments go to `panel serve`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_ROOT_USER_ACTION=ignore
python3 -m pip install -q -e .
port="${AMRA_PORT:-5006}"
echo "dashboard.sh: open http://localhost:${port}/main"
exec python3 -m panel serve app/main.py \
    --address "${AMRA_ADDRESS:-127.0.0.1}" --port "$port" --num-threads 0 \
    --allow-websocket-origin "localhost:${port}" --allow-websocket-origin "127.0.0.1:${port}" \
    "$@"
