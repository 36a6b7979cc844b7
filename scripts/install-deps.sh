#!/usr/bin/env bash
# Installs the Debian packages softhd needs to build, test, run the demo, draw its
# plots, build and test the Python module (pybind11, pytest, PyTorch for softhd.torch) and
# build the API reference (doxygen), make and check meshes (gmsh, python3-meshio: the
# program only, libgmsh is never linked), and only those that are missing.
# Safe to run again. --mpi adds Open MPI and PETSc (the SOFTHD_WITH_MPI build:
# libopenmpi-dev, openmpi-bin, petsc-dev).
set -euo pipefail

packages=(
  cmake make g++ pkg-config
  libeigen3-dev libnanoflann-dev libnlopt-cxx-dev libgtest-dev nlohmann-json3-dev
  libsuitesparse-dev libopenblas0-pthread
  libtrilinos-rol-dev libtrilinos-teuchos-dev libtrilinos-kokkos-dev
  python3 python3-matplotlib python3-numpy
  python3-dev pybind11-dev python3-pytest python3-torch
  clang libclang-rt-14-dev libomp-14-dev lld
  doxygen
  gmsh python3-meshio
)
if [ "${1:-}" = "--mpi" ]; then
  packages+=(libopenmpi-dev openmpi-bin petsc-dev)
elif [ $# -gt 0 ]; then
  echo "usage: scripts/install-deps.sh [--mpi]" >&2
  exit 2
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
