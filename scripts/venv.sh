# Sourced by dashboard.sh and test.sh: create (or reuse) the project virtual environment .venv
# with the first python3 >= 3.11 on PATH, Debian's own included (PEP 668 refuses system pip),
# and install AMRA into it (editable, so assets/ stay at the repo root) with the exact dependency
# versions of constraints.txt (the ones the tests passed on). Sets $PY.
# Usage: amra_venv EXTRAS   (e.g. "" or "test")
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_ROOT_USER_ACTION=ignore

amra_apt() {  # amra_apt PACKAGE...: install Debian packages as root, quietly, with a log on failure
    if [[ "$(id -u)" -ne 0 ]]; then
        echo "$(basename "$0"): missing Debian packages: $*; install them as root (apt-get install $*)" >&2
        return 1
    fi
    echo "$(basename "$0"): apt-get install $* ..."
    export DEBIAN_FRONTEND=noninteractive
    if ! { apt-get update -qq && apt-get install -y -qq --no-install-recommends "$@"; } >/tmp/amra-apt.log 2>&1; then
        tail -n 40 /tmp/amra-apt.log >&2
        echo "$(basename "$0"): FAILED: apt-get install $* (log: /tmp/amra-apt.log)" >&2
        return 1
    fi
}

amra_venv() {
    local extras="${1:-}" root venv base want stamp spec
    root="$(pwd -P)"
    venv="${AMRA_VENV:-$root/.venv}"
    base="$(command -v python3 || true)"
    if [[ -z "$base" ]] || ! "$base" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
        echo "$(basename "$0"): AMRA needs Python >= 3.11 as python3 on PATH (found: ${base:-none})" >&2
        return 1
    fi
    if [[ ! -x "$venv/bin/python" ]] || ! "$venv/bin/python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
        rm -rf "$venv"
        if ! "$base" -m venv "$venv" 2>/tmp/amra-venv.log; then
            # Debian ships venv/ensurepip separately
            rm -rf "$venv"
            amra_apt python3-venv || return 1
            "$base" -m venv "$venv" || return 1
        fi
    fi
    PY="$venv/bin/python"
    spec="."; [[ -n "$extras" ]] && spec=".[$extras]"
    stamp="$venv/.amra-install-$extras.stamp"
    want="$("$PY" --version 2>&1) $(cat pyproject.toml constraints.txt | sha256sum | cut -d' ' -f1) $root"
    if [[ -z "${AMRA_FORCE_INSTALL:-}" && -f "$stamp" && "$(cat "$stamp")" == "$want" ]] \
            && (cd / && "$PY" -c "import amra_core, app, pathlib, sys; sys.exit(pathlib.Path(app.__file__).resolve().parents[1] != pathlib.Path('$root'))") 2>/dev/null; then
        return 0
    fi
    echo "$(basename "$0"): installing AMRA into $venv (pip install -c constraints.txt -e '$spec') ..."
    local start=$SECONDS
    rm -f "$stamp"
    "$PY" -m pip install -q -U pip >/dev/null 2>&1 || true
    "$PY" -m pip install -q -c constraints.txt -e "$spec" || return 1
    echo "$want" >"$stamp"
    echo "$(basename "$0"): install took $((SECONDS - start)) s"
}
