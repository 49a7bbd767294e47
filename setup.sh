#!/usr/bin/env bash
# Set up petsc-contact on Debian 12 (as root), safe to run again; each step says what it does,
# after the seconds since the start, and skips what is already there:
#  1. Debian's PETSc library and headers, FFTW-MPI, Open MPI and a C compiler: the packages
#     dpkg does not list as installed, and only those, with apt-get;
#  2. a venv in ./.venv (from Debian's python3, no system site packages) with numpy 2;
#  3. petsc4py compiled there against Debian's PETSc and numpy 2 (about 3 minutes, once);
#  4. pyFFTW compiled against Debian's FFTW (its wheel's own FFTW is about 5% slower here);
#  5. the package with every extra (SurfaceTopography, mpi4py, mpi4py-fft, tests) from PyPI;
#  6. its numba kernels compiled into their cache, so that no run pays for it.
# PETSc itself is never built.  Another PETSc: set PETSC_DIR (and PETSC_ARCH) before running.
# `./setup.sh --packages-only` runs step 1 alone (tests/test_setup.py runs it with stand-in
# dpkg-query and apt-get); a failing apt-get stops the set-up with apt's message (exit != 0).
set -euo pipefail
cd "$(dirname "$0")"
export DEBIAN_FRONTEND=noninteractive
case "$#:${1-}" in
  0:) packages_only=false ;;
  1:--packages-only) packages_only=true ;;
  *) echo "usage: $0 [--packages-only]" >&2; exit 2 ;;
esac
say() { printf '[setup %4d s] %s\n' "$SECONDS" "$*"; }
# apt-get "$@", quiet unless it fails: then its output, one line saying what failed, and exit
apt_get() {
  local out status=0
  out=$(apt-get "$@" 2>&1) || status=$?
  if [ "$status" -ne 0 ]; then
    printf '%s\n' "$out" >&2
    echo "setup.sh: 'apt-get $*' failed (exit status $status); nothing after it was done" >&2
    exit "$status"
  fi
}

packages=(python3-venv python3-dev build-essential pkg-config libpetsc-real-dev
  libfftw3-dev libfftw3-mpi-dev libopenmpi-dev openmpi-bin)
missing=()
for p in "${packages[@]}"; do
  # "ii " is installed; a package dpkg has never seen makes dpkg-query fail (empty status)
  status=$(dpkg-query -W -f='${db:Status-Abbrev}' "$p" 2>/dev/null) || status=""
  # one "ii " is enough where several architectures of a package are listed
  case " $status" in *" ii "*) ;; *) missing+=("$p") ;; esac
done
if [ ${#missing[@]} -eq 0 ]; then
  say "1/6 Debian packages: all ${#packages[@]} installed"
else
  say "1/6 Debian packages: installing ${missing[*]} (apt-get update, apt-get install)"
  apt_get update -q
  apt_get install -y -q --no-install-recommends "${missing[@]}"
fi
apt_seconds=$SECONDS
if "$packages_only"; then
  exit 0
fi

export PETSC_DIR="${PETSC_DIR:-$(readlink -f /usr/lib/petsc)}" PETSC_ARCH="${PETSC_ARCH:-}"
if [ ! -f "$PETSC_DIR/include/petscversion.h" ]; then
  echo "setup.sh: no PETSc headers in PETSC_DIR=$PETSC_DIR (include/petscversion.h)" >&2
  exit 1
fi
petsc_version=$(awk '/define PETSC_VERSION_(MAJOR|MINOR) /{printf "%s%s", sep, $3; sep="."}' \
  "$PETSC_DIR/include/petscversion.h")

say "2/6 venv $(pwd)/.venv with numpy 2, setuptools and wheel"
# a venv from an earlier set-up that shared Debian's numpy-1 modules is replaced
if [ -f .venv/pyvenv.cfg ] && grep -q 'include-system-site-packages = true' .venv/pyvenv.cfg; then
  echo "replacing the old .venv (it used the system's numpy-1 modules)"
  rm -rf .venv
fi
[ -x .venv/bin/python ] || /usr/bin/python3 -m venv .venv
pip=(.venv/bin/python -m pip -q --disable-pip-version-check)
"${pip[@]}" install "numpy>=2" "setuptools>=61" wheel

# petsc4py of PETSc's own minor version, compiled here against numpy 2 (PyPI has no wheels):
# there when it was built for this PETSC_DIR and loads PETSc
petsc4py_check='import os, sys, petsc4py
version, petsc_dir = sys.argv[1:]
built_for = os.path.realpath(petsc4py.get_config()["PETSC_DIR"])
ok = petsc4py.__version__.startswith(version + ".") and built_for == os.path.realpath(petsc_dir)
from petsc4py import PETSc
sys.exit(not ok)'
if .venv/bin/python -c "$petsc4py_check" "$petsc_version" "$PETSC_DIR" 2>/dev/null; then
  say "3/6 petsc4py $petsc_version for $PETSC_DIR: already in .venv"
else
  say "3/6 petsc4py $petsc_version: compiling it against $PETSC_DIR (about 3 minutes, once)"
  "${pip[@]}" install --force-reinstall --no-deps --no-build-isolation --no-binary petsc4py \
    "petsc4py==$petsc_version.*"
fi

# pyFFTW linked against Debian's libfftw3 (a wheel's bundled copy has another name and path)
pyfftw_is_debians() {
  local so libs
  so=$(.venv/bin/python -c 'import pyfftw.pyfftw as m; print(m.__file__)' 2>/dev/null) || return 1
  libs=$(ldd "$so" 2>/dev/null) || return 1
  local debians='libfftw3\.so\.3 => (/usr)?/lib/'
  [[ $libs =~ $debians ]]
}
if pyfftw_is_debians; then
  say "4/6 pyFFTW linked against Debian's FFTW: already in .venv"
else
  say "4/6 pyFFTW: compiling it against Debian's FFTW"
  "${pip[@]}" install --force-reinstall --no-deps --no-binary pyfftw "pyFFTW>=0.13"
fi

say "5/6 petsc-contact with every extra: pip install -e \".[all]\""
"${pip[@]}" install -e ".[all]"
say "6/6 compiling the numba kernels into their cache"
.venv/bin/python -m petsc_contact.numerics.kernels
.venv/bin/petsc-contact --version
say "petsc-contact installed in $(pwd)/.venv: Debian packages ${apt_seconds} s," \
  "venv $((SECONDS - apt_seconds)) s"
