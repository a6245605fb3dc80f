#!/usr/bin/env bash
# Quick start, command 2: install everything the tests need on a fresh Debian machine (system
# packages with apt-get as root: chromium for the browser tests, buildah and debootstrap for the
# image tests), create/reuse .venv with AMRA and its test extras, then run the whole suite:
#   1. the core tests under NUMBA_BOUNDSCHECK=1 (own Numba cache): an out-of-bounds access in a
#      kernel raises IndexError instead of silently corrupting the heap. The tests marked slow are
#      long end-to-end runs through the same kernel paths (maps, validation report, 10 s runs);
#      bounds-checked kernels run them several times slower, so this pass leaves them to step 2;
#   2. every test (core, app, browser, slow) with the normal compiled kernels.
# Extra arguments go to both pytest runs, e.g. `bash scripts/test.sh -k trim`.
# AMRA_SKIP_BOUNDSCHECK=1 skips step 1 (local iterations only; CI runs both).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
source scripts/venv.sh

export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"  # debootstrap lives in /usr/sbin
need=()
[[ -x /usr/bin/chromium ]] || need+=(chromium)
command -v buildah >/dev/null || need+=(buildah)        # image tests: build and run the Dockerfile
command -v debootstrap >/dev/null || need+=(debootstrap)  # image tests: the local base image
if [[ ${#need[@]} -gt 0 ]]; then
    amra_apt "${need[@]}"
fi
amra_venv test

run_pytest() {  # exit code 5 (no tests collected) counts as a failure
    local rc=0
    "$PY" -m pytest "$@" || rc=$?
    if [[ $rc -eq 5 ]]; then
        echo "test.sh: pytest collected no tests: treating as failure" >&2
        return 1
    fi
    return $rc
}

if [[ -z "${AMRA_SKIP_BOUNDSCHECK:-}" ]]; then
    echo "test.sh: core tests under NUMBA_BOUNDSCHECK=1 ..."
    NUMBA_BOUNDSCHECK=1 NUMBA_CACHE_DIR="${AMRA_BC_CACHE:-$HOME/.cache/amra-numba-boundscheck}" \
        run_pytest -q -m "not slow" tests/core "$@"
fi
echo "test.sh: the whole suite ..."
run_pytest -ra "$@"
