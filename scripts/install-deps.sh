#!/usr/bin/env bash
# Installs every build, run and test dependency of vkloc from Debian 12 packages.
# Run as root. Idempotent: a second run installs nothing and only refreshes the
# package lists when they are missing or older than one day.
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build ccache pkg-config git clang-format
  # fuzzing (libFuzzer ships in compiler-rt) and symbolised sanitizer reports
  clang libclang-rt-dev llvm
  # Vulkan: loader + headers, lavapipe (CPU driver), validation layer, shader compilers
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  glslc glslang-tools spirv-tools
  # maths, images, meshes
  libglm-dev libeigen3-dev libopencv-dev libassimp-dev libdraco-dev libmeshoptimizer-dev libyaml-cpp-dev
  # command line, config, logging
  libcli11-dev nlohmann-json3-dev libfmt-dev
  # tests and benchmarks; a peer's data set with ground truth (ViSP Castle-simu)
  libgtest-dev libgmock-dev libbenchmark-dev visp-images-data
  # evaluation reports: plotting library inlined into the HTML
  libjs-chart.js
  # peer comparison (tests/visp, test-only, GPL-2): ViSP's model-based tracker
  libvisp-dev
)

if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps.sh: run as root (apt-get needs it), e.g. 'sudo bash scripts/install-deps.sh'" >&2
  exit 1
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps.sh: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

lists=/var/lib/apt/lists
if [ -z "$(find "$lists" -maxdepth 1 -name '*Packages*' -mmin -1440 2>/dev/null | head -n 1)" ]; then
  echo "install-deps.sh: refreshing package lists"
  apt-get update -qq
fi
echo "install-deps.sh: installing ${missing[*]}"
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
