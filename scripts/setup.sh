#!/usr/bin/env bash
# Installs the Debian 12 packages lambert needs (only those missing), then configures and
# builds the Release preset into build/ (with --distributed: OpenMPI and PETSc).
# Usage: scripts/setup.sh [preset]   (asan: clang, the sanitizer tests and the fuzz targets,
# into build-asan/). Compiles go through ccache, whose cache lives outside the clone.
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-release}"

packages=(build-essential cmake pkg-config libembree-dev libeigen3-dev libopenexr-dev
          libgtest-dev libcli11-dev zlib1g-dev nlohmann-json3-dev libcgal-dev
          pybind11-dev python3-dev python3-numpy python3-scipy python3-matplotlib python3-pytest
          ccache libopenmpi-dev openmpi-bin petsc-dev libtinygltf-dev chromium libexpat1-dev
          python3-meshio libassimp-dev)
# The asan preset builds with clang and links libFuzzer (from libclang-rt).
[[ "$preset" == asan ]] && packages+=(clang libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo_cmd=()
  [[ $(id -u) -eq 0 ]] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  "${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j"$(nproc)"
