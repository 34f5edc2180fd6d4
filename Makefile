# The two set-up commands of the README:
#   make run    installs what is missing, runs the default scene (Table 1 shot C3, plastic projectile in the
#               concrete target, default mesh) on $(NP) ranks into results/C3, the same shot with the rigid
#               projectile into results/C3-rigid, and the mesh with its picture into results/C3-mesh
#   make test   installs what is missing, lints, runs the fast unit lane and the system tests on $(WORKERS)
#               pytest-xdist workers each, then the system tests that start 2-rank processes (marked two_ranks)
#               one at a time (beside another worker's test, a 2-rank run waits on its descheduled rank at every
#               collective: 7x slower), then the MPI ones (marked mpi) on 2 ranks; the serial lanes leave the
#               mpi-marked tests to that last lane (on one rank their two runs would be one run twice)
PY := .venv/bin/python
NP ?= 2
# the unit and system lanes' pytest-xdist workers (one per core; tests in one xdist_group share a worker)
WORKERS ?= 2
# OpenMPI refuses to start as root unless told; CI and these machines run as root.
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
# ranks that wait yield the core (the system lane's xdist workers may run two 2-rank runs at once on 2 cores)
export OMPI_MCA_mpi_yield_when_idle := 1
export OMP_NUM_THREADS := 1

.PHONY: setup run test lint bench clean notebook setup-current test-current docs

setup:
	@bash tools/bootstrap.sh

# a user's shot has the cores to itself: its waiting rank spins, as under a plain mpirun (yielding costs a step
# 15-25 %)
run: export OMPI_MCA_mpi_yield_when_idle := 0
run: setup
	mpirun -n $(NP) $(PY) -m fepen run scenes/default.toml --out results/C3 --force
	$(PY) -m fepen run scenes/default.toml --set effects.fidelity=rigid --out results/C3-rigid --force
	$(PY) -m fepen mesh scenes/default.toml --out results/C3-mesh

# The tests' meshes go to one cache per user, shared by every checkout ($(TEST_MESHES); a set FEPEN_MESH_CACHE
# wins): CI on a kept machine and a fresh clone start warm instead of meshing everything again (a fresh clone
# with a cold cache spends a third of the suite in gmsh). Sharing is safe because an entry's key holds all that
# shapes its mesh: the exact shape record, the gmsh options, charge and mass, the gmsh version and a hash of
# the code that builds it (fepen/geometry/mesh.py _key, _code_hash: gmsh_model, shape, profile, tetra, cad,
# checks and the mass sizing), and an entry is read only after its sidecar's versions and SHA-256 match.
# Only `make test` uses it: fepen run and fepen mesh keep the checkout's meshes/cache.
TEST_MESHES ?= $(HOME)/.cache/fepen/test-meshes

test: setup
	$(PY) -m ruff check --no-cache fepen tests demos benchmarks tools
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} $(PY) -m pytest -q -m "not mpi" -n $(WORKERS) tests/unit
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} $(PY) -m pytest -q -m "not mpi and not two_ranks" \
	  -n $(WORKERS) --dist loadgroup --durations=20 tests/system
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} $(PY) -m pytest -q -m "not mpi and two_ranks" \
	  -p no:cacheprovider --durations=10 tests/system
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} mpirun -n $(NP) $(PY) -m pytest -q -m mpi \
	  -p no:cacheprovider tests

# The second stack (docs/install.md): the current dolfinx (0.11, PyPI's dolfinx-solver-real) on Python 3.12 with
# numpy 2 and MPICH, in .venv-current (tools/bootstrap_current.sh). Its lane: the unit lane, the MPI lane on 2
# ranks under MPICH's own mpiexec, and tests/stacks (Table 1 rigid and deformable at 6 mm on both
# stacks, the same numbers; it needs `make setup`'s .venv too). CI runs it after `make test` (.ci/run).
CURRENT := .venv-current/bin/python

setup-current:
	@bash tools/bootstrap_current.sh

test-current: setup setup-current
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} $(CURRENT) -m pytest -q -m "not mpi" -n $(WORKERS) tests/unit
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} .venv-current/bin/mpiexec -n $(NP) $(CURRENT) -m pytest -q \
	  -m mpi -p no:cacheprovider tests
	FEPEN_MESH_CACHE=$${FEPEN_MESH_CACHE:-$(TEST_MESHES)} $(CURRENT) -m pytest -q -p no:cacheprovider tests/stacks

# JupyterLab beside the kernel the set-up installs (fepen[notebook]: the pins that work with Debian's matplotlib);
# then `.venv/bin/jupyter lab demos/` and open api_tour.py or rigid_study.py as a notebook
notebook: setup
	$(PY) -m pip install -q --disable-pip-version-check -c tools/constraints.txt -e ".[test,parquet,notebook]"
	@echo "JupyterLab installed: .venv/bin/jupyter lab demos/   (right-click a .py demo: Open With > Notebook)"

# Every figure the docs quote, made again by the command that makes it and written back into its page
# (tools/make_docs.py: the blocks between <!-- make docs: NAME --> markers; `tools/make_docs.py --list` gives each
# block's cost on 2 cores and the total).
# `make docs ONLY="ricochet ballistic-limit"` makes the named ones.
docs: setup
	$(PY) tools/make_docs.py $(if $(ONLY),--only $(ONLY))

lint: setup
	$(PY) -m ruff check --no-cache fepen tests demos benchmarks tools

bench: setup
	$(PY) benchmarks/mesh_cost.py
	$(PY) benchmarks/wall_step_cost.py
	mpirun -n $(NP) $(PY) benchmarks/wall_step_cost.py 2.5
	$(PY) benchmarks/step_cost.py --ranks $(NP) --label "make bench"
	$(PY) benchmarks/rigid_shot.py
	$(PY) benchmarks/shot_cost.py 1 2

clean:
	rm -rf results meshes/cache .pytest_cache
