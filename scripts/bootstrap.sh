#!/usr/bin/env bash
# Prepare a machine to run and test dragposer-studio; `make run` and `make test` call it.
#
# 1. Debian runtime libraries that Qt 6 (xcb / offscreen platforms) and VTK need, plus
#    Xvfb for the viewport tests. Missing ones are installed with apt-get when running
#    as root; otherwise the script prints the one command to run and stops.
# 2. A virtual environment in .venv (created on first use).
# 3. `pip install -e '.[dev]'`, only when pyproject.toml changed since the last install
#    (its sha256 is kept in .venv/.pyproject.sha256).
# 4. The Khronos glTF validator (npm package gltf-validator, pinned) in .venv/gltf-validator,
#    which the glTF export tests run through node (docs/export.md). Node and npm come from
#    apt (nodejs, npm) when missing and running as root; without them, or offline, the
#    script says so and goes on: those tests then skip, saying why.
#
# Environment: PYTHON=/path/to/python3.11 picks the interpreter; DRAGPOSER_SKIP_APT=1
# skips step 1 (non-Debian machines, containers prepared by hand).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
VENV=.venv
STAMP="$VENV/.pyproject.sha256"

say() { printf 'bootstrap: %s\n' "$*" >&2; }
die() { say "error: $*"; exit 1; }

# Shared libraries loaded by PyQt6's xcb/offscreen plugins and VTK's OpenGL window,
# Mesa's software renderer for headless GL, and the virtual X server used by tests.
APT_PACKAGES=(
    libgl1 libegl1 libopengl0 libglx-mesa0 libgl1-mesa-dri
    libxkbcommon0 libxkbcommon-x11-0 libx11-xcb1 libxrender1 libxext6 libxt6
    libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0
    libxcb-shape0 libxcb-xinerama0 libxcb-xkb1 libxcb-randr0
    libdbus-1-3 libfontconfig1 libfreetype6 libglib2.0-0
    xvfb xauth
)

pick_python() {
    local candidate
    for candidate in "${PYTHON:-}" python3.11 python3; do
        [[ -n "$candidate" ]] || continue
        if command -v "$candidate" >/dev/null 2>&1 &&
            "$candidate" -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
            command -v "$candidate"
            return 0
        fi
    done
    return 1
}

installed() {
    [[ "$(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null)" == "installed" ]]
}

ensure_apt_packages() {
    local python=$1
    if [[ "${DRAGPOSER_SKIP_APT:-0}" == "1" ]]; then
        say "DRAGPOSER_SKIP_APT=1: not checking system packages"
        return 0
    fi
    if ! command -v dpkg-query >/dev/null 2>&1; then
        say "warning: not a Debian system (no dpkg-query); make sure Qt 6 xcb and OpenGL libraries are present"
        return 0
    fi
    local wanted=("${APT_PACKAGES[@]}") missing=() pkg
    # Debian's own python3.11 ships venv/ensurepip separately.
    if [[ "$python" == /usr/bin/* && ! -e "$VENV/bin/python" ]] &&
        ! "$python" -c 'import ensurepip, venv' >/dev/null 2>&1; then
        wanted+=(python3.11-venv)
    fi
    for pkg in "${wanted[@]}"; do
        installed "$pkg" || missing+=("$pkg")
    done
    [[ ${#missing[@]} -eq 0 ]] && return 0
    if [[ "$(id -u)" -ne 0 ]]; then
        say "error: missing system packages. Run this once as root, then retry:"
        printf '\n    sudo apt-get update && sudo apt-get install -y %s\n\n' "${missing[*]}" >&2
        exit 1
    fi
    say "installing system packages: ${missing[*]}"
    apt-get update -q
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
}

ensure_venv() {
    local python=$1
    if [[ -x "$VENV/bin/python" ]] && "$VENV/bin/python" -c '' 2>/dev/null; then
        return 0
    fi
    say "creating $VENV with $python"
    "$python" -m venv "$VENV" || die "could not create $VENV with $python"
}

ensure_project_installed() {
    local want have=""
    want=$(sha256sum pyproject.toml | cut -d' ' -f1)
    [[ -f "$STAMP" ]] && have=$(<"$STAMP")
    if [[ "$want" == "$have" ]] && [[ -x "$VENV/bin/dragposer-studio" ]]; then
        return 0
    fi
    say "installing the project into $VENV (pyproject.toml changed or first run)"
    # No --upgrade: torch stays at the pinned CPU wheel that pip's own config finds on disk.
    # pip warns once per missing folder of the machine's local index; that is not news.
    "$VENV/bin/python" -m pip install -q -e '.[dev]' \
        2> >(grep -v "is ignored: it is neither a file nor a directory" >&2) ||
        die "pip install -e '.[dev]' failed"
    printf '%s\n' "$want" >"$STAMP"
}

GLTF_VALIDATOR_VERSION=2.0.0-dev.3.10

ensure_gltf_validator() {
    local dir="$VENV/gltf-validator"
    if [[ -f "$dir/node_modules/gltf-validator/package.json" ]] &&
        grep -q "\"version\": \"$GLTF_VALIDATOR_VERSION\"" "$dir/node_modules/gltf-validator/package.json"; then
        return 0
    fi
    if ! command -v npm >/dev/null 2>&1 || ! command -v node >/dev/null 2>&1; then
        if [[ "${DRAGPOSER_SKIP_APT:-0}" != "1" && "$(id -u)" -eq 0 ]] && command -v apt-get >/dev/null 2>&1; then
            say "installing node and npm for the glTF validator"
            apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends nodejs npm ||
                say "warning: could not install nodejs/npm"
        fi
    fi
    if ! command -v npm >/dev/null 2>&1 || ! command -v node >/dev/null 2>&1; then
        say "warning: node/npm absent: the glTF validator tests will skip (install nodejs and npm)"
        return 0
    fi
    say "installing the Khronos glTF validator (npm gltf-validator $GLTF_VALIDATOR_VERSION) into $dir"
    mkdir -p "$dir"
    npm install --prefix "$dir" --no-audit --no-fund --silent "gltf-validator@$GLTF_VALIDATOR_VERSION" ||
        say "warning: npm could not install gltf-validator (offline?): the glTF validator tests will skip"
}

main() {
    local python
    python=$(pick_python) || die "Python 3.11 not found (install python3.11 or set PYTHON=/path/to/python3.11)"
    ensure_apt_packages "$python"
    ensure_venv "$python"
    ensure_project_installed
    ensure_gltf_validator
}

main "$@"
