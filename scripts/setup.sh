#!/usr/bin/env bash
# Installs what specchio needs on Debian 12 (bookworm), only where it is missing:
#   - Mesa lavapipe 25 (mesa-vulkan-drivers) from Debian's official bookworm-backports suite
#     (nothing else is taken from backports but what that package needs),
#   - the Vulkan loader (libvulkan1) and the Khronos validation layers,
#   - a C++ compiler for the glslang crate's build.
# On other distributions it installs nothing and says what to install when something is missing.
set -euo pipefail

log() { printf 'setup: %s\n' "$*" >&2; }

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"
    elif command -v sudo >/dev/null; then sudo "$@"
    else log "need root to run: $*"; exit 1
    fi
}

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "ok installed"; }
mesa_major() { dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | cut -d. -f1; }

if ! command -v cargo >/dev/null; then
    log "cargo (Rust >= 1.80) is required: install it with rustup (https://rustup.rs)"
    exit 1
fi

codename=$( . /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}" )
if [ "$codename" != "bookworm" ]; then
    if [ ! -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] ||
       ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
        log "not Debian 12: install Mesa >= 24 lavapipe, the Vulkan loader and the Khronos validation layers with your package manager"
    fi
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
missing=()
for p in libvulkan1 vulkan-validationlayers g++; do
    installed "$p" || missing+=("$p")
done
major=$(mesa_major || true)
need_mesa=0
if [ -z "$major" ] || [ "$major" -lt 25 ]; then need_mesa=1; fi

if [ ${#missing[@]} -gt 0 ] || [ $need_mesa -eq 1 ]; then
    if [ $need_mesa -eq 1 ] && ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
        log "adding the bookworm-backports suite (for Mesa 25 lavapipe)"
        as_root tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null <<'SRC'
Types: deb
URIs: http://deb.debian.org/debian
Suites: bookworm-backports
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SRC
    fi
    log "apt-get update"
    as_root apt-get update -qq
    if [ ${#missing[@]} -gt 0 ]; then
        log "installing ${missing[*]}"
        as_root apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    fi
    if [ $need_mesa -eq 1 ]; then
        log "installing mesa-vulkan-drivers from bookworm-backports"
        as_root apt-get install -y -qq --no-install-recommends -t bookworm-backports mesa-vulkan-drivers >/dev/null
    fi
fi
log "ready: mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers), vulkan-validationlayers $(dpkg-query -W -f='${Version}' vulkan-validationlayers)"
