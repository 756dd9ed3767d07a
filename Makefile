# The two commands of the README: `make lab` and `make test`.
VENV    ?= .venv
PYTHON  ?= python3
PY      := $(VENV)/bin/python
STAMP   := $(VENV)/.installed

# Headless rendering: VTK through EGL, pyvista as static images, no display needed.
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow
TEST_ENV := PYVISTA_JUPYTER_BACKEND=static PYVISTA_OFF_SCREEN=true

.PHONY: lab test test-numeric test-oldest e2e setup sysdeps lint clean

# As root (a container, a cloud VM) Jupyter refuses to start without --allow-root.
LAB_FLAGS := $(if $(filter 0,$(shell id -u 2>/dev/null)),--allow-root,)

lab: setup
	$(VENV)/bin/jupyter lab $(LAB_FLAGS) notebooks/

# One worker per core; loadscope keeps a notebook's cells (and a module's tests) on one worker.
JOBS ?= $(shell nproc 2>/dev/null || echo 2)

test: setup
	$(TEST_ENV) $(PY) -m pytest -n $(JOBS) --dist loadscope --nbval-lax --nbval-current-env \
	  --ignore=tests/e2e tests notebooks assignments

# The oldest supported Python (requires-python >=3.10) with the lower bounds of the core
# dependencies (see the comment in pyproject.toml): the library's own tests, none that need
# pyvista, matplotlib, Jupyter or ipywidgets, run from the source tree (PYTHONPATH=.) with no
# install of the package. --confcutdir=tests keeps the root conftest.py (nbval's, it imports
# nbformat) out. Skipped, and says why, where no Python 3.10 runs.
OLDEST_VENV  ?= .venv-oldest
OLDEST_PINS  := numpy==1.23.5 scipy==1.14.0 pooch==1.8.0 'pytest>=8.0' 'hypothesis>=6.100'
OLDEST_TESTS := $(wildcard tests/test_rotations_*.py) tests/test_swing_twist.py \
	tests/test_skeleton.py tests/test_fk.py tests/test_bvh.py tests/test_bvh_errors.py \
	tests/test_motion.py tests/test_ik_geometry.py tests/test_ik_solvers.py \
	tests/test_ik_robustness.py tests/test_retarget.py tests/test_keyframes.py \
	tests/test_keyframes_motion.py tests/test_keyframes_rotations.py tests/test_mass_spring.py \
	tests/test_foot_sliding.py \
	tests/test_robustness_library.py tests/test_robustness_io.py tests/test_data.py

test-oldest:
	@py=""; \
	for c in python3.10 $$(pyenv root 2>/dev/null)/versions/3.10*/bin/python3.10 /usr/bin/python3.10; do \
	  if "$$c" -c 'import sys; assert sys.version_info[:2] == (3, 10)' >/dev/null 2>&1; then py=$$c; break; fi; \
	done; \
	if [ -z "$$py" ]; then \
	  echo "test-oldest: skipped: no Python 3.10 on this machine (the oldest that requires-python allows)"; \
	  exit 0; \
	fi; \
	start=$$(date +%s); \
	if [ ! -f $(OLDEST_VENV)/.installed ] || [ Makefile -nt $(OLDEST_VENV)/.installed ]; then \
	  rm -rf $(OLDEST_VENV) && "$$py" -m venv $(OLDEST_VENV) && \
	  $(OLDEST_VENV)/bin/python -m pip install --quiet $(OLDEST_PINS) > $(OLDEST_VENV)/install.log 2>&1 \
	    || { cat $(OLDEST_VENV)/install.log; exit 1; }; \
	  touch $(OLDEST_VENV)/.installed; \
	fi; \
	echo "test-oldest: $$($(OLDEST_VENV)/bin/python -c 'import sys, numpy, scipy, pooch; print("Python", sys.version.split()[0], "numpy", numpy.__version__, "scipy", scipy.__version__, "pooch", pooch.__version__)')"; \
	status=0; PYTHONPATH=. $(OLDEST_VENV)/bin/python -m pytest -q -p no:cacheprovider --confcutdir=tests \
	  $(OLDEST_TESTS) || status=$$?; \
	echo "test-oldest: $$(( $$(date +%s) - start )) s, install included"; \
	exit $$status

# The notebooks' checked outputs and the library tests that compare floats, again, on this
# machine's alternate numeric path (tests/numeric_paths.py: an older OpenBLAS kernel, numpy's
# baseline SIMD, another BLAS thread count; printed first): what they print and assert must
# not depend on which kernel rounded last, since another CPU rounds differently. About a
# minute on 2 cores.
test-numeric: setup
	$(TEST_ENV) $(PY) tests/numeric_paths.py -- $(PY) -m pytest -n $(JOBS) --dist loadscope \
	  --nbval-lax --nbval-current-env notebooks $(OLDEST_TESTS) tests/test_numeric_paths.py

# The browser test: JupyterLab in headless Chromium (Debian's package; never a downloaded build).
e2e: setup
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "Installing chromium for the browser test..."; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium >/dev/null; \
	  else echo "warning: the browser test needs chromium (apt-get install chromium)"; fi; }
	$(TEST_ENV) $(PY) -m pytest -q --durations=12 tests/e2e

lint: setup
	$(VENV)/bin/ruff check .

setup: sysdeps $(STAMP)

$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@echo "Installing the course into $(VENV) (first time: about 2 minutes)..."
	@$(PY) -m pip install --quiet --upgrade pip > $(VENV)/install.log 2>&1 || (cat $(VENV)/install.log; exit 1)
	@$(PY) -m pip install --quiet -e '.[dev]' >> $(VENV)/install.log 2>&1 || (cat $(VENV)/install.log; exit 1)
	@touch $@

# pip's VTK wheel needs libGL.so.1 and libEGL.so.1; a bare Debian lacks them. The grader's
# strongest sandbox needs bubblewrap (bwrap) and libseccomp. When any is missing, install them
# when we can (root with apt-get), otherwise say what is missing.
sysdeps:
	@if command -v ldconfig >/dev/null 2>&1; then \
	  missing=""; \
	  for lib in libGL.so.1:libgl1 libEGL.so.1:libegl1 libseccomp.so.2:libseccomp2; do \
	    ldconfig -p | awk '{print $$1}' | grep -qxF "$${lib%%:*}" || missing="$$missing $${lib#*:}"; \
	  done; \
	  command -v bwrap >/dev/null 2>&1 || missing="$$missing bubblewrap"; \
	  if [ -n "$$missing" ]; then \
	    if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	      echo "Installing$$missing (3D rendering off screen, the grader's sandbox)..."; \
	      apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $$missing >/dev/null; \
	    else \
	      echo "warning: missing$$missing; apt-get install$$missing (3D views, the grader's sandbox)"; \
	    fi; \
	  fi; \
	fi

clean:
	rm -rf $(VENV) $(OLDEST_VENV) .pytest_cache .ruff_cache .mypy_cache .hypothesis
