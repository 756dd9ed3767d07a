#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder's image (its Ubuntu base
# image), with the bundle unpacked in $AUTOGRADER_ROOT/source. It installs exactly what
# grading needs: the Python and numpy versions the bundle was built with (bundle.env), and
# bubblewrap + libseccomp, the sandbox's strongest level (docs/sandbox.md).
#
# AUTOGRADER_SETUP_DRY_RUN=1 checks every step and installs nothing; its last step then runs
# with $AUTOGRADER_PYTHON (a Python that has numpy) if that is set.
set -euo pipefail

ROOT="${AUTOGRADER_ROOT:-/autograder}"
SOURCE="$ROOT/source"
DRY="${AUTOGRADER_SETUP_DRY_RUN:-}"

say() { echo "setup: $*"; }
fail() { echo "setup: error: $*" >&2; exit 1; }
run() {  # a step that changes the machine: only shown in a dry run
    if [ -n "$DRY" ]; then say "would run: $*"; else say "running: $*"; "$@"; fi
}

say "1/5 the bundle is whole"
[ -f "$SOURCE/bundle.env" ] || fail "$SOURCE/bundle.env is missing: unzip the bundle there"
# shellcheck source=/dev/null
. "$SOURCE/bundle.env"
[[ "${ASSIGNMENT:-}" =~ ^[a-z0-9_]+$ ]] || fail "bundle.env: ASSIGNMENT is '${ASSIGNMENT:-}'"
[[ "${PYTHON_VERSION:-}" =~ ^3\.[0-9]+$ ]] || fail "bundle.env: PYTHON_VERSION is '${PYTHON_VERSION:-}'"
[[ "${NUMPY_VERSION:-}" =~ ^[0-9]+(\.[0-9]+)+$ ]] || fail "bundle.env: NUMPY_VERSION is '${NUMPY_VERSION:-}'"
for f in run_autograder seed autograder/__init__.py autograder/gradescope/run.py \
         "autograder/assignments/$ASSIGNMENT.py" course/__init__.py; do
    [ -f "$SOURCE/$f" ] || fail "the bundle has no $f"
done
[ -s "$SOURCE/seed" ] || fail "the bundle's seed file is empty"
PY="python$PYTHON_VERSION"
VENV="$ROOT/venv"
say "assignment $ASSIGNMENT, Python $PYTHON_VERSION, numpy $NUMPY_VERSION"

say "2/5 system packages: Python $PYTHON_VERSION, bubblewrap, libseccomp2"
PACKAGES=("$PY" "$PY-venv" bubblewrap libseccomp2)
if ! command -v apt-get >/dev/null; then
    [ -n "$DRY" ] || fail "no apt-get: this script is for Gradescope's Ubuntu images"
    say "  no apt-get on this machine: the packages are looked up on the image"
fi
if [ -z "$DRY" ]; then
    apt-get update -qq
    if ! apt-cache show "$PY-venv" >/dev/null 2>&1; then  # not this Ubuntu's own Python
        run env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
            software-properties-common
        run add-apt-repository -y ppa:deadsnakes/ppa
        apt-get update -qq
    fi
fi
KNOWN="$( (apt-cache show "${PACKAGES[@]}" 2>/dev/null || true) | sed -n 's/^Package: //p')"
for p in "${PACKAGES[@]}"; do
    if grep -qx "$p" <<<"$KNOWN"; then say "  $p: in the package lists"
    elif [ -n "$DRY" ]; then say "  $p: not in this machine's package lists (python: from ppa:deadsnakes on the image)"
    else fail "apt has no package $p"; fi
done
run env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    "${PACKAGES[@]}"

say "3/5 the grader's Python: $VENV with numpy==$NUMPY_VERSION"
if [ -n "$DRY" ] && ! command -v "$PY" >/dev/null; then say "  $PY is installed by step 2"; fi
[ -n "$DRY" ] || [ ! -e "$VENV" ] || fail "$VENV exists already"
run "$PY" -m venv "$VENV"
run "$VENV/bin/python" -m pip install --quiet --no-cache-dir "numpy==$NUMPY_VERSION"

say "4/5 only root reads the bundle and its seed (submissions run as another user)"
[ "$(id -u)" = 0 ] || [ -n "$DRY" ] || fail "run this as root"
run chown -R 0:0 "$SOURCE"
run chmod -R go-rwx "$SOURCE"
run chmod 0400 "$SOURCE/seed"
run chmod 0700 "$ROOT"

say "5/5 the grader runs: pinned versions, the assignment's cases, the sandbox"
CHECK="$VENV/bin/python"
if [ -n "$DRY" ]; then CHECK="${AUTOGRADER_PYTHON:-}"; fi
if [ -z "$CHECK" ]; then
    say "  skipped in this dry run (set AUTOGRADER_PYTHON to a Python with numpy to check it)"
else
    (cd "$SOURCE" && "$CHECK" -B -c "from autograder.gradescope.run import check_install; check_install()")
fi
say "done${DRY:+ (dry run: nothing was installed)}"
