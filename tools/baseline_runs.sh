#!/usr/bin/env bash
# The runs whose summary.json and history.csv must not change under a refactor (issue 12's check):
# C3 and C7 (plastic, 4 mm), a rigid C7, the charged 800 m/s shot (4 mm), the copper Taylor test, and the
# twins of the rigid and deformable run (layers, wear, erosion: tools/baseline/), each on 1 and 2 ranks. Usage: tools/baseline_runs.sh OUTDIR [SOURCE_TREE]
#   compare two such directories with tools/compare_results.py A B
set -euo pipefail
out=$(realpath -m "$1"); src=$(realpath "${2:-$(dirname "$0")/..}")
py=${PY:-$src/.venv/bin/python}; [ -x "$py" ] || py=/work/main/.venv/bin/python
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMP_NUM_THREADS=1
export PYTHONPATH="$src"
cd "$src"
mkdir -p "$out"
run() {  # name scene sets...
  local name=$1 scene=$2; shift 2
  for n in 1 2; do
    local sets=(); for s in "$@"; do sets+=(--set "$s"); done
    local cmd=("$py" -m fepen run "$scene" --out "$out/$name-np$n" "${sets[@]}")
    [ "$n" = 2 ] && cmd=(mpirun -n 2 "${cmd[@]}")
    echo "== $name on $n rank(s)"; "${cmd[@]}" > "$out/$name-np$n.log" 2>&1 || echo "   exit $?"
  done
}
run C3-plastic scenes/default.toml impact.shot=C3 mesh.size=0.004
run C7-plastic scenes/default.toml impact.shot=C7 mesh.size=0.004
run C7-rigid scenes/default.toml impact.shot=C7 effects.fidelity=rigid
run charged-800 demos/charge/charge_800.toml mesh.size=0.004
run taylor-copper demos/verification/taylor_copper.toml
run C7-rigid-wear scenes/default.toml impact.shot=C7 effects.fidelity=rigid effects.wear=true
run layered-rigid tools/baseline/layered_concrete.toml effects.fidelity=rigid impact.velocity=800
run layered-plastic tools/baseline/layered_metal.toml impact.velocity=800 impact.obliquity_deg=5 mesh.size=0.004 \
  run.fields=false run.end_time=1.5e-4
run mild-wear-erosion scenes/mild-1300.toml mesh.size=0.006 run.end_time=2e-4 run.fields=false
