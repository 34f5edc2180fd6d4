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

if ! /usr/bin/python3 -c "import dolfinx, h5py, numba, matplotlib, venv" >/dev/null 2>&1 \
   || ! ldconfig -p | grep -q libOSMesa \
   || ! command -v mpirun >/dev/null 2>&1; then
  echo "[bootstrap] installing Debian packages (dolfinx 0.5.2 and friends)"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $apt_pkgs >/dev/null
fi

# ParaView (pvpython, pvbatch) and xvfb-run: tests/system/test_paraview.py opens the fields as a user does.
# Optional: where apt cannot install them, those tests are skipped and say why.
if ! command -v pvpython >/dev/null 2>&1 || ! command -v xvfb-run >/dev/null 2>&1; then
  echo "[bootstrap] installing ParaView and xvfb (Debian packages) for the field-reader tests"
  { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq paraview xvfb >/dev/null; } \
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
echo "[bootstrap] installing fepen and its PyPI dependencies into .venv"
.venv/bin/python -m pip install -q --disable-pip-version-check -c tools/constraints.txt -e ".[test]"
echo "$want" > "$stamp"
