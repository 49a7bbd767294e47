#!/usr/bin/env bash
# Set up petsc-contact on Debian 12 (as root), safe to run again:
#  1. Debian's PETSc library and headers, FFTW-MPI, Open MPI and a C compiler (apt);
#  2. a venv in ./.venv (from Debian's python3, no system site packages) with numpy 2;
#  3. petsc4py compiled there against Debian's PETSc and numpy 2 (about 3 minutes, once);
#  4. pyFFTW compiled against Debian's FFTW (its wheel's own FFTW is about 5% slower here);
#  5. the package with every extra (SurfaceTopography, mpi4py, mpi4py-fft, tests) from PyPI.
# PETSc itself is never built.  Another PETSc: set PETSC_DIR (and PETSC_ARCH) before running.
set -euo pipefail
cd "$(dirname "$0")"
export DEBIAN_FRONTEND=noninteractive
packages=(python3-venv python3-dev build-essential pkg-config libpetsc-real-dev
  libfftw3-dev libfftw3-mpi-dev libopenmpi-dev openmpi-bin)
if dpkg-query -W -f '${db:Status-Abbrev} ${Package}\n' "${packages[@]}" 2>&1 | grep -qv '^ii '; then
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
fi

export PETSC_DIR="${PETSC_DIR:-$(readlink -f /usr/lib/petsc)}" PETSC_ARCH="${PETSC_ARCH:-}"
petsc_version=$(awk '/define PETSC_VERSION_(MAJOR|MINOR) /{printf "%s%s", sep, $3; sep="."}' \
  "$PETSC_DIR/include/petscversion.h")

# a venv from an earlier set-up that shared Debian's numpy-1 modules is replaced
if [ -f .venv/pyvenv.cfg ] && grep -q 'include-system-site-packages = true' .venv/pyvenv.cfg; then
  echo "replacing the old .venv (it used the system's numpy-1 modules)"
  rm -rf .venv
fi
[ -x .venv/bin/python ] || /usr/bin/python3 -m venv .venv
pip=(.venv/bin/python -m pip -q --disable-pip-version-check)
"${pip[@]}" install "numpy>=2" "setuptools>=61" wheel
# petsc4py of PETSc's own minor version, compiled here against numpy 2 (PyPI has no wheels)
if ! .venv/bin/python -c "import petsc4py, sys; sys.exit(not petsc4py.__version__.startswith('$petsc_version.'))" 2>/dev/null; then
  echo "compiling petsc4py $petsc_version against $PETSC_DIR (about 3 minutes)"
  "${pip[@]}" install --no-build-isolation --no-binary petsc4py "petsc4py==$petsc_version.*"
fi
if ! ldd .venv/lib/python3*/site-packages/pyfftw/pyfftw*.so 2>/dev/null | grep -q "libfftw3.so.3 => /"; then
  "${pip[@]}" install --no-binary pyfftw "pyFFTW>=0.13"
fi
"${pip[@]}" install -e ".[all]"
.venv/bin/petsc-contact --version
echo "petsc-contact installed in $(pwd)/.venv"
