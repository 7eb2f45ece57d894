#!/usr/bin/env bash
# Installs what snowbake needs on Debian 12, if it is missing. Idempotent: does nothing (and
# needs no network) when every package is already there. Runs apt-get as root, or through sudo.
# `time` (GNU time) measures the peak memory tests/memory_model_test.cpp and
# tools/measure-memory.sh compare with the memory model.
# pybind11-dev, python3-dev, python3-pytest, python3-numpy and python3-openimageio are for the
# optional Python module (-DSNOWBAKE_PYTHON=ON, python/) and its pytest.
# libopenmpi-dev and openmpi-bin are for the distributed decomposition (distributed/,
# docs/distributed.md) and its tests under mpirun on localhost.
# slurm-wlm and munge are for the Slurm tests (tests/farm/slurm_array_test.sh, a job array, and
# tests/distributed/srun_bake_test.sh, srun --mpi=pmix), which start their own single-node Slurm;
# the bake itself never needs them.
# --with-blender also installs Blender 3.4, which the test suite uses as a real client of the
# outputs (tests/blender_test.cpp); the bake itself never needs it.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libopenvdb-dev libboost-iostreams-dev libassimp-dev
  libopenimageio-dev libtbb-dev libgtest-dev libcli11-dev nlohmann-json3-dev
  libtomlplusplus-dev libgdal-dev
  libopenmpi-dev openmpi-bin
  time
  pybind11-dev python3-dev python3-pytest python3-numpy python3-openimageio
  slurm-wlm munge
)
# Blender's glTF importer imports numpy, which Debian's blender only recommends.
if [ "${1:-}" = "--with-blender" ]; then packages+=(blender python3-numpy); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages present"
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then as_root=(); elif command -v sudo >/dev/null; then as_root=(sudo); else
  echo "setup: missing packages (${missing[*]}) and not root: run this script as root" >&2
  exit 1
fi
echo "setup: installing ${missing[*]}"
"${as_root[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
