#!/bin/sh
# Installs what `make demo`, `make check` and `make bench` need beyond a C
# compiler: Bullet, ODE, libccd, FCL (the engines Minko is compared with and
# plugs into), Check (unit tests), pkg-config and gnuplot (plots).
#   scripts/install-deps.sh          install whatever is missing (apt-get; sudo when not root)
#   scripts/install-deps.sh --check  exit 0 if everything is present, 1 otherwise (installs nothing)
# `make lib` needs none of this.
set -eu

PACKAGES="libbullet-dev libode-dev libccd-dev libfcl-dev check pkg-config gnuplot-nox g++"

missing() {
    m=""
    command -v pkg-config >/dev/null 2>&1 || { echo "pkg-config"; return; }
    for mod in bullet bullet-float64 ode ccd fcl check; do
        pkg-config --exists "$mod" 2>/dev/null || m="$m $mod"
    done
    command -v gnuplot >/dev/null 2>&1 || m="$m gnuplot"
    command -v c++ >/dev/null 2>&1 || m="$m c++"
    echo "$m"
}

m=$(missing)
if [ "${1:-}" = "--check" ]; then
    [ -z "$m" ]
    exit $?
fi
if [ -z "$m" ]; then
    echo "install-deps: everything is already installed."
    exit 0
fi

echo "install-deps: missing:$m"
if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-deps: this is not a Debian/Ubuntu system (no apt-get)." >&2
    echo "install-deps: install these yourself: Bullet 3 (with its float64 variant), ODE (double), libccd, FCL, Check, pkg-config, gnuplot, a C++ compiler." >&2
    exit 1
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
        echo "install-deps: not root and no sudo; run as root: apt-get install -y $PACKAGES" >&2
        exit 1
    fi
fi
echo "install-deps: installing with apt-get: $PACKAGES"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get install -y --no-install-recommends $PACKAGES || {
    $SUDO apt-get update && $SUDO apt-get install -y --no-install-recommends $PACKAGES
}
m=$(missing)
if [ -n "$m" ]; then
    echo "install-deps: still missing after install:$m" >&2
    exit 1
fi
echo "install-deps: done."
