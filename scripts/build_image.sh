#!/usr/bin/env bash
# Build the AMRA image without a Docker engine (buildah, chroot isolation), as the tests do.
#   bash scripts/build_image.sh [TAG]        (default TAG: localhost/amra:test)
# 1. A local Debian bookworm base with python3 (debootstrap), made once and cached under
#    $AMRA_BASE_CACHE (default /var/tmp/amra-base), imported as localhost/pybase:bookworm.
# 2. `buildah bud --layers --format docker` (the OCI format drops HEALTHCHECK) of the Dockerfile on
#    that base: the dependency layer is reused until
#    pyproject.toml changes. The host's CA bundle is mounted (the registry is reached through it)
#    and a package index from the host's pip configuration, if it names one, is passed as a build
#    arg (file:// indexes are host paths and are not passed).
# Needs root and the Debian packages buildah and debootstrap. Prints the build time.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
TAG="${1:-localhost/amra:test}"
BASE_IMAGE=localhost/pybase:bookworm
CACHE="${AMRA_BASE_CACHE:-/var/tmp/amra-base}"
MIRROR="${AMRA_DEBIAN_MIRROR:-http://deb.debian.org/debian}"

export PATH="$PATH:/usr/local/sbin:/usr/sbin:/sbin"  # debootstrap lives in /usr/sbin
for tool in buildah debootstrap; do
    command -v "$tool" >/dev/null || { echo "build_image.sh: $tool is missing (apt-get install buildah debootstrap)" >&2; exit 1; }
done

if ! buildah inspect --type image "$BASE_IMAGE" >/dev/null 2>&1; then
    mkdir -p "$CACHE"
    if [[ ! -f "$CACHE/rootfs/.amra-complete" ]]; then
        echo "build_image.sh: debootstrap bookworm -> $CACHE/rootfs (once, ~2-3 min) ..."
        rm -rf "$CACHE/rootfs.partial"
        debootstrap --variant=minbase --include=python3,python3-venv,python3-pip,ca-certificates \
            bookworm "$CACHE/rootfs.partial" "$MIRROR" >"$CACHE/debootstrap.log" 2>&1 \
            || { tail -n 20 "$CACHE/debootstrap.log" >&2; exit 1; }
        rm -rf "$CACHE/rootfs.partial/var/cache/apt/archives/"*.deb
        touch "$CACHE/rootfs.partial/.amra-complete"
        rm -rf "$CACHE/rootfs"
        mv "$CACHE/rootfs.partial" "$CACHE/rootfs"
    fi
    echo "build_image.sh: importing $BASE_IMAGE ..."
    ctr=$(buildah from scratch)
    buildah copy --quiet "$ctr" "$CACHE/rootfs" / >/dev/null
    buildah config --env PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
        --cmd /bin/bash "$ctr"
    buildah commit --quiet --rm "$ctr" "$BASE_IMAGE" >/dev/null
fi

args=(--build-arg "BASE=$BASE_IMAGE")
index="$(pip config get global.index-url 2>/dev/null || true)"
extra="$(pip config get global.extra-index-url 2>/dev/null | tr ' ' '\n' | grep -E '^https?://' | tr '\n' ' ' || true)"
[[ -n "${PIP_INDEX_URL:-$index}" ]] && args+=(--build-arg "PIP_INDEX_URL=${PIP_INDEX_URL:-$index}")
[[ -n "${extra// /}" ]] && args+=(--build-arg "PIP_EXTRA_INDEX_URL=${extra% }")
[[ -n "${NUMBA_CPU_NAME_BUILD:-}" ]] && args+=(--build-arg "NUMBA_CPU_NAME=$NUMBA_CPU_NAME_BUILD")
certs=()
[[ -f /etc/ssl/certs/ca-certificates.crt ]] && certs=(-v /etc/ssl/certs/ca-certificates.crt:/etc/ssl/certs/ca-certificates.crt:ro)

start=$SECONDS
buildah bud --isolation chroot --layers --format docker "${certs[@]}" "${args[@]}" -t "$TAG" . >&2
echo "build_image.sh: built $TAG in $((SECONDS - start)) s"
