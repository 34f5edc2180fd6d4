#!/usr/bin/env bash
# Install what fepen needs, once. A second run checks and returns in seconds.
#   - Debian bookworm packages: dolfinx 0.5.2 (real), h5py, numba, matplotlib, OpenMPI, and the X/GL
#     libraries that PyPI's gmsh and VTK wheels load.
#   - A virtual environment .venv on /usr/bin/python3 with --system-site-packages, so that it sees Debian's
#     dolfinx; numpy is held at Debian's version by tools/constraints.txt (numpy 2 breaks petsc4py).
#   - Debian's ParaView 5.11 and xvfb, for the tests that open the fields with a real ParaView.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"

apt_pkgs="gcc python3-dolfinx-real python3-h5py python3-numba python3-matplotlib python3-venv python3-pip \
openmpi-bin libglu1-mesa libxcursor1 libxft2 libxinerama1 libgl1 libegl1 libosmesa6"

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi

# What is missing, from dpkg's own records: no pipe (under pipefail, `ldconfig -p | grep -q` failed at random when
# grep exited at its first match and ldconfig died of SIGPIPE, so an installed machine ran apt again), and apt only
# when a package is really absent (a user without sudo or network can run an installed machine).
missing() {
  local pkg status
  for pkg in "$@"; do
    status=$(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null || true)
    if [ "$status" != "installed" ]; then printf '%s ' "$pkg"; fi
  done
}

need=$(missing $apt_pkgs)
if [ -n "$need" ]; then
  echo "[bootstrap] installing Debian packages: $need"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $need >/dev/null
fi
if ! /usr/bin/python3 -c "import dolfinx, h5py, numba, matplotlib, venv" >/dev/null 2>&1; then
  echo "[bootstrap] Debian's python3-dolfinx-real and friends are installed but do not import:" >&2
  /usr/bin/python3 -c "import dolfinx, h5py, numba, matplotlib, venv" >&2 || true
  exit 1
fi

# ParaView (pvpython, pvbatch) and xvfb-run: tests/system/test_paraview.py opens the fields as a user does.
# Optional: where apt cannot install them, those tests are skipped and say why.
need=$(missing paraview xvfb)
if [ -n "$need" ]; then
  echo "[bootstrap] installing ParaView and xvfb (Debian packages) for the field-reader tests"
  { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq $need >/dev/null; } \
    || echo "[bootstrap] ParaView could not be installed: its tests will be skipped"
fi

stamp=.venv/.fepen-stamp
want=$(cat pyproject.toml tools/constraints.txt | sha256sum | cut -c1-16)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
if [ ! -x .venv/bin/python ]; then
  echo "[bootstrap] creating .venv (system site packages visible)"
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
# Debian's h5py 3.7.0 is installed under the distribution name h5py._debian_h5py_serial, which pip does not take for
# "h5py": it would build PyPI's h5py from source against Debian's HDF5 (and fail) to meet fepen's "h5py>=3.7". A
# record of the name pip looks for, pointing at nothing, says that Debian's is there (numpy, scipy, numba,
# matplotlib and mpi4py need none: Debian records them under their own names).
site=$(.venv/bin/python -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
h5=$(/usr/bin/python3 -c "import h5py; print(h5py.__version__)")
if [ ! -d "$site/h5py-$h5.dist-info" ]; then
  mkdir -p "$site/h5py-$h5.dist-info"
  printf 'Metadata-Version: 2.1\nName: h5py\nVersion: %s\nSummary: Debian'"'"'s python3-h5py (a record for pip)\n' "$h5" \
    > "$site/h5py-$h5.dist-info/METADATA"
  echo "debian" > "$site/h5py-$h5.dist-info/INSTALLER"
  : > "$site/h5py-$h5.dist-info/RECORD"
fi
echo "[bootstrap] installing fepen and its PyPI dependencies into .venv"
.venv/bin/python -m pip install -q --disable-pip-version-check -c tools/constraints.txt -e ".[test,parquet]"
echo "$want" > "$stamp"
