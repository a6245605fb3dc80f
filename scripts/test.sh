#!/usr/bin/env bash
# Install everything AMRA's tests need on a fresh Debian machine (Python 3.11 + pip),
# then run the whole suite (core, app, slow end-to-end and headless-browser tests).
# Idempotent: a second run skips the installs. Extra arguments go to pytest,
# e.g. `bash scripts/test.sh -k placeholder`. AMRA_FORCE_INSTALL=1 redoes the pip step.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_ROOT_USER_ACTION=ignore
CHROMIUM=/usr/bin/chromium

# 1. Headless Chromium for the browser tests (Playwright cannot download its own here).
if [[ ! -x "$CHROMIUM" ]]; then
    if [[ "$(id -u)" -ne 0 ]]; then
        echo "test.sh: $CHROMIUM is missing; install Debian's 'chromium' package as root" >&2
        exit 1
    fi
    echo "test.sh: installing chromium with apt-get ..."
    start=$SECONDS
    export DEBIAN_FRONTEND=noninteractive
    if ! { apt-get update -qq && apt-get install -y -qq --no-install-recommends chromium; } >/tmp/amra-apt.log 2>&1; then
        tail -n 40 /tmp/amra-apt.log >&2
        echo "test.sh: FAILED to apt-get install chromium (log: /tmp/amra-apt.log)" >&2
        exit 1
    fi
    [[ -x "$CHROMIUM" ]] || { echo "test.sh: chromium installed but $CHROMIUM not found" >&2; exit 1; }
    echo "test.sh: chromium installed in $((SECONDS - start)) s: $("$CHROMIUM" --version 2>/dev/null || true)"
fi

# 2. The project (editable: assets/ stay at the repo root) and its test extras.
root="$(pwd -P)"
stamp=".amra-install.stamp"
want="$(python3 --version 2>&1) $(sha256sum pyproject.toml | cut -d' ' -f1) $root"
installed_here() {
    # Skip the pip step only if this exact pyproject was installed from this checkout
    # and the editable install still resolves `app` to this repo.
    [[ -z "${AMRA_FORCE_INSTALL:-}" && -f "$stamp" && "$(cat "$stamp")" == "$want" ]] || return 1
    (cd / && python3 - "$root" <<'PY'
import pathlib, sys
import app, playwright, pytest_playwright, pytest_timeout  # noqa: F401
root = pathlib.Path(sys.argv[1])
sys.exit(pathlib.Path(app.__file__).resolve().parent.parent != root)
PY
    ) >/dev/null 2>&1
}
if installed_here; then
    echo "test.sh: amra[test] already installed from $root"
else
    echo "test.sh: pip install -e .[test] ..."
    start=$SECONDS
    rm -f "$stamp"
    python3 -m pip install -q -e ".[test]"
    echo "$want" >"$stamp"
    echo "test.sh: pip step took $((SECONDS - start)) s"
fi

# 3. The whole suite. Exit code 5 (no tests collected) counts as a failure.
rc=0
python3 -m pytest -ra "$@" || rc=$?
if [[ $rc -eq 5 ]]; then
    echo "test.sh: pytest collected no tests: treating as failure" >&2
    exit 1
fi
exit $rc
