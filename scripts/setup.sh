#!/usr/bin/env bash
# Installs what specchio needs on Debian 12 (bookworm), only where it is missing:
#   - Mesa lavapipe 25 (mesa-vulkan-drivers) from Debian's official bookworm-backports suite
#     (nothing else is taken from backports but what that package needs),
#   - the Vulkan loader (libvulkan1) and the Khronos validation layers,
#   - glslang's compiler, glslangValidator (glslang-tools), which compiles the shaders,
#   - a C++ compiler for nv-flip-sys's build (FLIP, the image metric),
#   - Xvfb, xdotool and the X client libraries winit loads (the viewer's tests),
#   - weston, whose headless backend is the Wayland compositor of the viewer's Wayland test,
#   - openbox, a window manager, for the viewer's test of a minimised window,
#   - Google's SwiftShader Vulkan driver, the second CPU driver, unpacked project-locally into
#     .drivers/swiftshader/ from Debian's chromium-common package (Chromium is not installed),
#   - the Python side: a project-local venv, .venv/, with maturin (builds the `specchio`
#     Python package, python/), numpy, pytest and Ray (docs/python.md).
# On other distributions it installs nothing and says what to install when something is missing.
#
# `scripts/setup.sh --main-job [BENCH ARGUMENTS...]` (what scripts/run.sh runs) sets up only what
# the main job uses: the Vulkan loader and layers, lavapipe 25, glslang's compiler and the C++
# compiler; SwiftShader only when the arguments name it; no X, Wayland, FUSE or Python, which
# only the tests and the Python package use (on a fresh machine the venv alone fetches Ray).
set -euo pipefail
cd "$(dirname "$0")/.."

main_job=0
want_swiftshader=1
if [ "${1:-}" = "--main-job" ]; then
    main_job=1
    shift
    want_swiftshader=0
    for a in "$@"; do
        case "$a" in *swiftshader*|*SwiftShader*) want_swiftshader=1 ;; esac
    done
fi

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

# SwiftShader, project-local: chromium-common ships it as libvk_swiftshader.so with its ICD
# manifest. apt-get download checks the package against the signed archive index; we compare
# its SHA256 with the index once more before unpacking the two files. .cargo/config.toml
# points the Vulkan loader at the manifest (VK_ADD_DRIVER_FILES) for cargo run and cargo test.
swiftshader_dir=.drivers/swiftshader
provide_swiftshader() {
    if [ -e "$swiftshader_dir/vk_swiftshader_icd.json" ] && [ -e "$swiftshader_dir/libvk_swiftshader.so" ]; then
        return 0
    fi
    if [ -z "$(apt-cache policy chromium-common 2>/dev/null | sed -n 's/^ *Candidate: *//p' | grep -v '(none)')" ]; then
        log "apt-get update (for chromium-common, which carries SwiftShader)"
        as_root apt-get update -qq
    fi
    local version tmp deb want got
    version=$(apt-cache policy chromium-common | sed -n 's/^ *Candidate: *//p')
    if [ -z "$version" ] || [ "$version" = "(none)" ]; then
        log "chromium-common is not in the apt sources: SwiftShader not provided (lavapipe only)"
        return 0
    fi
    tmp=$(mktemp -d)
    log "providing SwiftShader from chromium-common $version into $swiftshader_dir"
    chmod 755 "$tmp"
    chown _apt "$tmp" 2>/dev/null || true # apt downloads as the _apt user where it can
    (cd "$tmp" && apt-get download -qq "chromium-common=$version")
    deb=$(ls "$tmp"/chromium-common_*.deb)
    want=$(apt-cache show "chromium-common=$version" | sed -n 's/^SHA256: //p' | head -n 1)
    got=$(sha256sum "$deb" | cut -d' ' -f1)
    if [ -z "$want" ] || [ "$want" != "$got" ]; then
        log "chromium-common $version: SHA256 $got does not match the archive's ${want:-(none)}"
        rm -rf "$tmp"
        exit 1
    fi
    mkdir -p "$tmp/x"
    dpkg-deb --fsys-tarfile "$deb" |
        tar -x -C "$tmp/x" ./usr/lib/chromium/libvk_swiftshader.so ./usr/lib/chromium/vk_swiftshader_icd.json
    # Into place only whole: a half-copied driver must not look present next time.
    mkdir -p .drivers
    rm -rf "$swiftshader_dir.new"
    mkdir "$swiftshader_dir.new"
    cp "$tmp/x/usr/lib/chromium/libvk_swiftshader.so" "$tmp/x/usr/lib/chromium/vk_swiftshader_icd.json" "$swiftshader_dir.new/"
    echo "chromium-common $version sha256 $got" > "$swiftshader_dir.new/SOURCE"
    rm -rf "$swiftshader_dir"
    mv "$swiftshader_dir.new" "$swiftshader_dir"
    rm -rf "$tmp"
}

provide_python() {
    [ $main_job -eq 1 ] && return 0
    # rosbags and mcap: the independent readers of the ROS 2 bags (python/tests/test_bag.py).
    scripts/python-venv.sh .venv "import maturin, numpy, pytest, ray, rosbags, mcap" \
        "maturin>=1.9,<2" "numpy>=2" "pytest>=7" "ray>=2.9" "rosbags>=0.10,<1" "mcap>=1.2,<2"
}

codename=$( . /etc/os-release 2>/dev/null && echo "${VERSION_CODENAME:-}" )
if [ "$codename" != "bookworm" ]; then
    if [ ! -e "$swiftshader_dir/vk_swiftshader_icd.json" ]; then
        log "not Debian 12: SwiftShader is not provided; put libvk_swiftshader.so and vk_swiftshader_icd.json in $swiftshader_dir to test on it"
    fi
    if [ ! -e /usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json ] ||
       ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; then
        log "not Debian 12: install Mesa >= 24 lavapipe, the Vulkan loader and the Khronos validation layers with your package manager"
    fi
    if ! command -v glslangValidator >/dev/null && [ -z "${GLSLANG_VALIDATOR:-}" ]; then
        log "not Debian 12: install glslang's compiler, glslangValidator (it compiles the shaders), or name it with GLSLANG_VALIDATOR=PATH"
    fi
    provide_python
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
missing=()
# xvfb, xdotool and the X client libraries winit loads at run time: the viewer tests (tests/cli/viewer.rs)
# run `specchio view` in a virtual X server; weston (headless) is their Wayland compositor, and
# brings the Wayland client libraries winit loads; openbox minimises a window as a desktop does.
# fusefat, dosfstools and fuse: a vfat mounted through FUSE, where case folds and each spelling
# has its own inode (tests/cli/case_folding.rs).
packages=(libvulkan1 vulkan-validationlayers glslang-tools g++)
if [ $main_job -eq 0 ]; then
    packages+=(xvfb xdotool weston openbox libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 fusefat dosfstools fuse)
fi
for p in "${packages[@]}"; do
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
[ $want_swiftshader -eq 1 ] && provide_swiftshader
provide_python
if [ $main_job -eq 0 ]; then
    log "ready: Python venv .venv ($(.venv/bin/python -c 'import sys, numpy, ray; print(f"Python {sys.version.split()[0]}, numpy {numpy.__version__}, Ray {ray.__version__}")'))"
fi
log "ready: SwiftShader $(cut -d' ' -f2 "$swiftshader_dir/SOURCE" 2>/dev/null || echo 'not provided')"
log "ready: mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers), vulkan-validationlayers $(dpkg-query -W -f='${Version}' vulkan-validationlayers)"
