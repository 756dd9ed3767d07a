# The two commands of the README: `make lab` and `make test`.
VENV    ?= .venv
PYTHON  ?= python3
PY      := $(VENV)/bin/python
STAMP   := $(VENV)/.installed

# Headless rendering: VTK through EGL, pyvista as static images, no display needed.
export VTK_DEFAULT_OPENGL_WINDOW ?= vtkEGLRenderWindow
TEST_ENV := PYVISTA_JUPYTER_BACKEND=static PYVISTA_OFF_SCREEN=true

.PHONY: lab test e2e setup sysdeps lint clean

# As root (a container, a cloud VM) Jupyter refuses to start without --allow-root.
LAB_FLAGS := $(if $(filter 0,$(shell id -u 2>/dev/null)),--allow-root,)

lab: setup
	$(VENV)/bin/jupyter lab $(LAB_FLAGS) notebooks/

test: setup
	$(TEST_ENV) $(PY) -m pytest --nbval-lax --nbval-current-env --ignore=tests/e2e tests notebooks assignments

# The browser test: JupyterLab in headless Chromium (Debian's package; never a downloaded build).
e2e: setup
	@command -v chromium >/dev/null 2>&1 || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "Installing chromium for the browser test..."; \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends chromium >/dev/null; \
	  else echo "warning: the browser test needs chromium (apt-get install chromium)"; fi; }
	$(TEST_ENV) $(PY) -m pytest -q tests/e2e

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
	rm -rf $(VENV) .pytest_cache .ruff_cache .hypothesis
