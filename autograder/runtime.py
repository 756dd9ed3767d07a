"""The one Python a submission gets on Linux: a minimal copy of this interpreter.

:func:`staged` lays out, once per interpreter, numpy and child (and reuses while they are
unchanged), a folder whose ``jail/`` is a root file system holding only what a submission
may run, at the paths the child sees::

    jail/sandbox/python/bin/python3     this interpreter's binary
    jail/sandbox/python/lib/*.so*       the shared libraries it, its modules and numpy load
    jail/sandbox/python/lib/python3.X/  its standard library, less what runs native code or
                                        other interpreters (ctypes, tkinter,
                                        subinterpreters, test modules) and every
                                        site-packages
    jail/sandbox/lib/numpy, numpy.libs  numpy
    jail/sandbox/runtime/               the child's two files (child.py, protocol.py)
    jail/sandbox/work/                  the submissions' folders (the ``chroot`` level)
    jail/<the dynamic loader's path>    the loader the binary names

Files are hard links where the file system allows (copies otherwise), readable by everyone,
so that a sandbox user other than the grader's can run it. The bubblewrap sandbox binds the
parts of it into a root file system of its own; the ``chroot`` level enters ``jail/``
itself. Either way there is no second interpreter, no shell and no site-packages to find.

Everything lives in the grader's own :func:`workspace`, never in a folder that ``$TMPDIR``
names as it is: a private ``$TMPDIR`` (mode 0700, as ``mktemp -d`` or systemd's PrivateTmp
give) would keep the sandbox user out of the runtime, and a grader that then fell back to a
weaker level would fail open.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
import subprocess
import sys
import sysconfig
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

VERSION = "2"  # bump when the layout changes
CHILD_FILES = (Path(__file__).with_name("child.py"), Path(__file__).with_name("protocol.py"))
WORKSPACE_ENV = "AUTOGRADER_WORKSPACE"  # a folder to hold the workspace instead of /var/tmp
# Standard-library packages and modules left out: native code and other interpreters first;
# then what only takes room (tests, tools, the installers).
LEFT_OUT = frozenset({
    "ctypes", "tkinter", "turtle.py", "turtledemo", "idlelib", "test", "ensurepip", "venv",
    "lib2to3", "distutils", "pydoc_data", "site-packages", "dist-packages", "__phello__",
})
# Extension modules (by the name before the first dot) left out of lib-dynload.
LEFT_OUT_EXTENSIONS = ("_ctypes", "_tkinter", "_xxsubinterpreters", "_xxinterpchannels",
                       "_xxinterpqueues", "_interpreters", "_interpchannels", "_interpqueues",
                       "_test", "xxsubtype", "xxlimited", "_xxtestfuzz", "_multiprocessing",
                       "_posixsubprocess", "_socket", "_ssl", "readline", "_curses")


@dataclass(frozen=True)
class Runtime:
    """Where a staged runtime is: ``root`` holds ``jail/``, whose ``sandbox/`` holds
    ``python/`` and ``lib/``; ``loader`` is the dynamic loader the binary names (it appears at
    that same path inside the jail)."""

    root: Path
    loader: str
    version: str  # "3.11", the standard library's folder is python/lib/python<version>

    @property
    def jail(self) -> Path:
        return self.root / "jail"

    @property
    def sandbox(self) -> Path:
        return self.jail / "sandbox"

    @property
    def python_home(self) -> Path:
        return self.sandbox / "python"

    @property
    def python(self) -> Path:
        return self.python_home / "bin" / "python3"

    @property
    def libs(self) -> Path:
        return self.python_home / "lib"

    @property
    def numpy_path(self) -> Path:
        return self.sandbox / "lib"

    @property
    def stdlib(self) -> Path:
        return self.libs / f"python{self.version}"

    @property
    def work(self) -> Path:
        """The folder of the submissions' own folders at the ``chroot`` level."""
        return self.sandbox / "work"


def workspace() -> Path:
    """The grader's own folder, made now if need be: ``autograder-<uid>`` (mode 0711) in the
    first of ``$AUTOGRADER_WORKSPACE``, ``/var/tmp``, ``/tmp`` and the temporary folder
    whose every ancestor anyone may pass through, so that the sandbox user can reach the
    runtime in it, and nothing else of the host through it.

    Raises OSError, saying what to do, when no such folder exists or the workspace found
    there is not this user's alone.
    """
    if os.name != "posix":
        return Path(tempfile.gettempdir())
    chosen = os.environ.get(WORKSPACE_ENV)
    candidates = [chosen] if chosen else ["/var/tmp", "/tmp", tempfile.gettempdir()]
    for c in candidates:
        parent = Path(os.path.realpath(c))
        if _passable(parent):
            break
    else:
        raise OSError(f"no folder for the grader's workspace: {' and '.join(candidates)} "
                      "cannot be passed through by other users (each folder on the way needs "
                      f"o+x); set {WORKSPACE_ENV} to one that can")
    path = parent / f"autograder-{os.getuid()}"
    try:
        os.mkdir(path, 0o711)
    except FileExistsError:
        pass
    st = os.lstat(path)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.getuid() or st.st_mode & 0o022:
        raise OSError(f"{path} is not this grader's own folder (owner {st.st_uid}, mode "
                      f"{stat.S_IMODE(st.st_mode):o}): remove it, or set {WORKSPACE_ENV}")
    os.chmod(path, 0o711)  # traversable, not listable
    return path


def _passable(folder: Path) -> bool:
    """Whether every folder from ``/`` to ``folder`` (a real path) lets others through."""
    here = Path("/")
    for part in ("", *folder.parts[1:]):
        here = here / part
        try:
            st = os.stat(here)
        except OSError:
            return False
        if not stat.S_ISDIR(st.st_mode) or not st.st_mode & 0o001:
            return False
    return True


def _sources() -> tuple[Path, Path, Path, list[Path]]:
    """The interpreter's binary, libpython's folder, the standard library, numpy's folders."""
    python = Path(os.path.realpath(sys.executable))
    libdir = Path(sysconfig.get_config_var("LIBDIR") or python.parent.parent / "lib")
    stdlib = Path(os.path.realpath(os.path.dirname(os.__file__)))
    pkg = Path(np.__file__).resolve().parent
    return python, libdir, stdlib, [pkg, *pkg.parent.glob("numpy.libs")]


def _key() -> str:
    python, _, stdlib, numpy_dirs = _sources()
    parts = [VERSION, str(python), str(python.stat().st_mtime_ns), str(stdlib),
             *(str(d) for d in numpy_dirs), np.__version__,
             *(hashlib.sha256(f.read_bytes()).hexdigest() for f in CHILD_FILES)]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]


@cache
def staged() -> Runtime:
    """The runtime for this interpreter, staged now if it is not there yet (about a second;
    later calls, and later graders with the same interpreter and numpy, reuse it).

    Raises OSError when it cannot be staged (no ``ldd``, say).
    """
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    home = workspace()
    final = home / f"runtime-{_key()}"
    if _trusted(final):
        return Runtime(final, (final / "loader").read_text(), version)
    work = Path(tempfile.mkdtemp(prefix=f"{final.name}.", dir=home))
    try:
        loader = _stage(work, version)
        (work / "loader").write_text(loader)
        (work / "complete").touch()
        os.chmod(work, 0o755)
        try:
            os.rename(work, final)
        except OSError:  # another grader staged it first (or a stranger's folder is there)
            if not _trusted(final):
                return Runtime(work, loader, version)  # ours, used from where it is
            shutil.rmtree(work, ignore_errors=True)
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    return Runtime(final, loader, version)


def _trusted(folder: Path) -> bool:
    """A complete runtime that this user owns and nobody else can have changed."""
    try:
        st = os.lstat(folder)
    except OSError:
        return False
    return (stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid()
            and not st.st_mode & 0o022 and (folder / "complete").is_file())


def _stage(root: Path, version: str) -> str:
    python, libdir, stdlib, numpy_dirs = _sources()
    rt = Runtime(root, "", version)
    bin_dir = rt.python.parent
    bin_dir.mkdir(parents=True)
    _place(python, rt.python)
    _tree(stdlib, rt.stdlib, _stdlib_filter)
    for d in numpy_dirs:
        _tree(d, rt.numpy_path / d.name, _numpy_filter)
    sandbox = rt.sandbox
    natives = [rt.python, *sorted(sandbox.rglob("*.so")), *sorted(sandbox.rglob("*.so.*"))]
    libs, loader = _shared_libraries(natives, inside=sandbox)
    for name in ("libpython*.so*",):  # a shared interpreter's library, if any
        for f in libdir.glob(name):
            libs.setdefault(f.name, f)
    for name, src in libs.items():
        if not (rt.libs / name).exists():
            _place(src, rt.libs / name)
    (sandbox / "runtime").mkdir()
    for f in CHILD_FILES:  # explicit modes: the grader's copy may be root's alone (setup.sh)
        (sandbox / "runtime" / f.name).write_bytes(f.read_bytes())
        os.chmod(sandbox / "runtime" / f.name, 0o644)
    in_jail = rt.jail / loader.lstrip("/")
    in_jail.parent.mkdir(parents=True, exist_ok=True)
    _place(Path(os.path.realpath(loader)), in_jail)
    rt.work.mkdir()
    (rt.jail / "dev").mkdir()
    if os.geteuid() == 0:  # the chroot level's /dev/null (bubblewrap brings its own /dev)
        try:
            os.mknod(rt.jail / "dev" / "null", stat.S_IFCHR | 0o666, os.makedev(1, 3))
            os.chmod(rt.jail / "dev" / "null", 0o666)  # past the umask
        except OSError:  # no CAP_MKNOD: the child reads a closed pipe instead
            pass
    for d in [root, *(p for p in root.rglob("*") if p.is_dir() and not p.is_symlink())]:
        os.chmod(d, 0o755)
    os.chmod(rt.work, 0o711)  # the submissions' folders: reachable by name, not listed
    return loader


def _stdlib_filter(rel: Path) -> bool:
    top = rel.parts[0]
    if top in LEFT_OUT or top.startswith("config-"):
        return False
    if top == "lib-dynload" and len(rel.parts) > 1:
        return not rel.parts[1].split(".")[0].startswith(LEFT_OUT_EXTENSIONS)
    return True


def _numpy_filter(rel: Path) -> bool:
    return "tests" not in rel.parts and rel.suffix not in (".pyi", ".h", ".c", ".pxd")


def _tree(src: Path, dst: Path, keep: Callable[[Path], bool]) -> None:
    """Hard links (or copies) of the files below ``src`` that ``keep`` their relative path."""
    for here, dirs, files in os.walk(src):
        rel = Path(here).relative_to(src)
        dirs[:] = [d for d in dirs if keep(rel / d)]
        (dst / rel).mkdir(parents=True, exist_ok=True)
        for f in files:
            if keep(rel / f) and os.path.isfile(os.path.join(here, f)):
                _place(Path(here) / f, dst / rel / f)


def _place(src: Path, dst: Path) -> None:
    """A hard link of ``src`` where it is readable by everyone and writable by its owner
    alone (a link to a file others may write would let them change the runtime), else a
    readable copy."""
    mode = os.stat(src).st_mode
    if mode & 0o004 and not mode & 0o022:
        try:
            os.link(src, dst)
            return
        except OSError:  # another file system, or links not allowed here
            pass
    shutil.copyfile(src, dst)
    os.chmod(dst, 0o755 if mode & 0o111 else 0o644)


def _shared_libraries(files: list[Path], inside: Path) -> tuple[dict[str, Path], str]:
    """The shared libraries ``files`` load (found by ``ldd``), by file name, except those
    already ``inside`` the runtime, and the dynamic loader's path."""
    ldd = shutil.which("ldd")
    if ldd is None:
        raise OSError("ldd is not installed: cannot find the libraries the interpreter needs")
    libs: dict[str, Path] = {}
    loader = ""
    for i in range(0, len(files), 200):
        out = subprocess.run([ldd, *map(str, files[i:i + 200])], capture_output=True,
                             text=True, check=False).stdout
        for line in out.splitlines():
            line = line.strip()
            if "=>" in line:
                path = line.split("=>", 1)[1].split("(")[0].strip()
                if path.startswith("/") and not Path(path).resolve().is_relative_to(inside):
                    libs.setdefault(Path(path).name, Path(os.path.realpath(path)))
            elif line.startswith("/") and "(0x" in line and "ld-" in line:
                loader = line.split("(")[0].strip()
    if not loader:
        raise OSError("ldd did not name the dynamic loader")
    return libs, loader
