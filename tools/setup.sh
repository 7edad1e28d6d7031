#!/usr/bin/env bash
# Installs the Debian 12 packages talus needs to build, test and plot. Idempotent and non-interactive:
# packages already present are skipped, so a second run costs a second.
# `tools/setup.sh --with-clang` adds clang and LLVM's OpenMP runtime, for tools/check_builds.sh.
set -euo pipefail

packages=(
  cmake g++ make ninja-build
  libeigen3-dev libhdf5-dev libvtk9-dev nlohmann-json3-dev libgtest-dev
  libcli11-dev libfmt-dev libhwy-dev libopenmpi-dev openmpi-bin
  python3-matplotlib python3-numpy python3-vtk9 python3-jsonschema hdf5-tools
)
case "${1:-}" in
  "") ;;
  --with-clang) packages+=(clang libomp-dev) ;;
  *) echo "setup: unknown option '$1'; the one option is --with-clang" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
