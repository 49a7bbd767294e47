#!/usr/bin/env bash
# Set up petsc-contact on Debian 12 (as root): Debian's PETSc/petsc4py and friends, then the
# package into ./.venv (made from /usr/bin/python3 with system site packages, so that it
# sees Debian's petsc4py), with SurfaceTopography and its numpy 1.26 from PyPI.  Safe to run
# again.
set -euo pipefail
cd "$(dirname "$0")"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends \
  python3-petsc4py python3-mpi4py python3-mpi4py-fft python3-pyfftw python3-numpy \
  python3-scipy python3-h5py python3-matplotlib python3-numba python3-pytest python3-venv python3-pip \
  python3-setuptools openmpi-bin libfftw3-mpi3 >/dev/null
[ -x .venv/bin/python ] || /usr/bin/python3 -m venv --system-site-packages .venv
# SurfaceTopography (instrument files) needs numpy >= 1.26, which Debian's numba refuses:
# numpy 1.26 and numba from PyPI in the venv; Debian's compiled modules keep working with
# numpy 1.26 (measured: docs/measured.md)
.venv/bin/pip install -q --disable-pip-version-check \
  "numpy==1.26.4" "numba==0.68.1" "SurfaceTopography==1.18.2" 2>&1 | grep -v -i "warning" || true
.venv/bin/pip install -q --no-build-isolation --no-deps -e . 2>&1 | grep -v -i "warning" || true
.venv/bin/petsc-contact --help >/dev/null
echo "petsc-contact installed in $(pwd)/.venv"
