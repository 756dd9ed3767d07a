"""The one Python a submission gets on Linux: a minimal copy of this interpreter.

:func:`staged` lays out, once per interpreter and numpy (and reuses while they are
unchanged), a folder holding only what a submission may run::

    python/bin/python3          this interpreter's binary
    python/lib/*.so*            the shared libraries it, its modules and numpy load (ldd)
    python/lib/python3.X/       its standard library, less what runs native code or other
                                interpreters (ctypes, tkinter, subinterpreters, test modules)
                                and every site-packages
    lib/numpy, lib/numpy.libs   numpy

Files are hard links where the file system allows (copies otherwise), readable by everyone,
so that a sandbox user other than the grader's can run it. In the bubblewrap sandbox this
folder is the whole file system besides the dynamic loader, the child's two files and the
working directory: there is no second interpreter, no shell and no site-packages to find.
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

VERSION = "1"  # bump when the layout changes
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
    """Where a staged runtime is: ``root`` holds ``python/`` and ``lib/``; ``loader`` is the
    dynamic loader the binary names (it must appear at that same path)."""

    root: Path
    loader: str
    version: str  # "3.11", the standard library's folder is python/lib/python<version>

    @property
    def python(self) -> Path:
        return self.root / "python" / "bin" / "python3"

    @property
    def libs(self) -> Path:
        return self.root / "python" / "lib"

    @property
    def numpy_path(self) -> Path:
        return self.root / "lib"

    @property
    def stdlib(self) -> Path:
        return self.libs / f"python{self.version}"


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
             *(str(d) for d in numpy_dirs), np.__version__]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]


@cache
def staged() -> Runtime:
    """The runtime for this interpreter, staged now if it is not there yet (about a second;
    later calls, and later graders with the same interpreter and numpy, reuse it).

    Raises OSError when it cannot be staged (no ``ldd``, say).
    """
    version = f"{sys.version_info.major}.{sys.version_info.minor}"
    home = Path(tempfile.gettempdir())
    final = home / f"autograder-runtime-{os.getuid()}-{_key()}"
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
    bin_dir = root / "python" / "bin"
    lib = root / "python" / "lib"
    bin_dir.mkdir(parents=True)
    _place(python, bin_dir / "python3")
    _tree(stdlib, lib / f"python{version}", _stdlib_filter)
    for d in numpy_dirs:
        _tree(d, root / "lib" / d.name, _numpy_filter)
    natives = [bin_dir / "python3", *sorted(root.rglob("*.so")), *sorted(root.rglob("*.so.*"))]
    libs, loader = _shared_libraries(natives, inside=root)
    for name in ("libpython*.so*",):  # a shared interpreter's library, if any
        for f in libdir.glob(name):
            libs.setdefault(f.name, f)
    for name, src in libs.items():
        if not (lib / name).exists():
            _place(src, lib / name)
    for d in [root, *(p for p in root.rglob("*") if p.is_dir() and not p.is_symlink())]:
        os.chmod(d, 0o755)
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
    """A hard link of ``src`` where it is readable by everyone, else a readable copy."""
    mode = os.stat(src).st_mode
    if mode & 0o004:
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
