#!/usr/bin/env bash
# Installs every Debian 12 package hemi needs to build, test, benchmark and draw its plots.
# Idempotent: packages already present are left alone, and apt-get update runs only when
# something is missing. Run as root (or with sudo available).
set -euo pipefail

packages=(
    # toolchain
    build-essential cmake ninja-build pkg-config
    # Vulkan: loader + headers, Mesa lavapipe (software Vulkan), Khronos validation layers, tools
    libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools spirv-tools
    # volk: the test of an engine that loads Vulkan with it (tests/volk/), and samples/engine's loader
    libvulkan-volk-dev
    # samples/engine's window (GLFW), and the X server its tests present to without a display (xvfb-run)
    libglfw3-dev xvfb xauth
    # shaders
    glslang-tools glslang-dev
    # math, scene and image formats
    libglm-dev libeigen3-dev libtinygltf-dev nlohmann-json3-dev libstb-dev libopenexr-dev libimath-dev
    # JPEG textures: libjpeg-turbo (PNG stays with stb_image)
    libjpeg62-turbo-dev
    # zlib: the tests write PNGs of any depth (tests/png_writer.h)
    zlib1g-dev
    # Debian 12's Imath CMake config names its Python binding library; without it every configure warns
    python3-imath
    # baking
    libembree-dev libtbb-dev
    # command line, hashing (xxHash, header-only)
    libcli11-dev libxxhash-dev
    # distributed bakes: hemi-bake under mpirun (optional for the build; the tests run it when it is there)
    libopenmpi-dev openmpi-bin
    # tests and benchmarks; clang's libFuzzer and sanitizer runtimes for the fuzz preset
    libgtest-dev libgmock-dev libbenchmark-dev clang libclang-rt-14-dev
    # GNU time: bench/level_scaling.sh reads each rank's peak memory with /usr/bin/time
    time
    # a real game level for the lightmap tests: OpenArena 0.8.1's Quake III maps (pak1-maps.pk3, 40 MB;
    # openarena-data would also pull in the game's textures, models and sounds, 350 MB)
    openarena-081-maps
    # a second, sealed indoor level from OpenArena's community map pack (oacmpdm1; 36 MB, and the 0.8.8
    # patch data it depends on, 73 MB)
    openarena-oacmp1
    # real HDRIs for the lightmap tests: Blender's studio-light worlds (Poly Haven, CC0), 31 MB, data only
    blender-data
    # formatting check (.ci/format)
    clang-format
    # plots
    gnuplot-nox
)

missing=()
for p in "${packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$p")
    fi
done

if [ ${#missing[@]} -eq 0 ]; then
    echo "install_deps: all ${#packages[@]} packages present"
    exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install_deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
