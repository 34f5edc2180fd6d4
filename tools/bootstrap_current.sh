#!/usr/bin/env bash
# The second stack, once: fepen on the current dolfinx (0.11) with numpy 2 and MPICH, in .venv-current.
#   - Python 3.12 or later: $FEPEN_PYTHON, else python3.13/python3.12 that run, else pyenv's 3.12/3.13.
#   - dolfinx-solver-real 0.11.0.post0 from PyPI: dolfinx with real PETSc, petsc4py, ufl, basix, ffcx, mpi4py
#     and MPICH as wheels (a community build, not the FEniCS project's own; docs/install.md names the others).
#   - fepen itself, editable, with its test tools (pip resolves numpy 2, numba, scipy, h5py, matplotlib, gmsh).
# Nothing of Debian's is used: no --system-site-packages. A second run checks its stamp and returns at once.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
venv=${VENV_CURRENT:-.venv-current}
dolfinx_pin="dolfinx-solver-real==0.11.0.post0"

runs() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 12))' >/dev/null 2>&1; }
find_python() {
  local c
  for c in "${FEPEN_PYTHON:-}" python3.13 python3.12; do
    [ -n "$c" ] && command -v "$c" >/dev/null 2>&1 && runs "$c" && { command -v "$c"; return; }
  done
  for c in "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.1[23]*/bin/python3; do
    [ -x "$c" ] && runs "$c" && { echo "$c"; return; }
  done
  return 1
}

stamp=$venv/.fepen-stamp
want=$( (cat pyproject.toml; echo "$dolfinx_pin") | sha256sum | cut -c1-16)
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
if [ ! -x "$venv/bin/python" ]; then
  py=$(find_python) || { echo "[bootstrap-current] no Python 3.12 or later found (set FEPEN_PYTHON)" >&2; exit 1; }
  echo "[bootstrap-current] creating $venv with $py ($("$py" --version))"
  "$py" -m venv "$venv"
fi
echo "[bootstrap-current] installing $dolfinx_pin and fepen with its test tools into $venv"
"$venv/bin/python" -m pip install -q --disable-pip-version-check "$dolfinx_pin"
"$venv/bin/python" -m pip install -q --disable-pip-version-check -e ".[test]"
"$venv/bin/python" -c "from mpi4py import MPI; import dolfinx, numpy; print('[bootstrap-current] dolfinx',
dolfinx.__version__, 'numpy', numpy.__version__, '|', MPI.Get_library_version().splitlines()[0].strip())"
echo "$want" > "$stamp"
