"""The sandboxed side: load one submission, call its functions on inputs, report results.

Run by :mod:`autograder.sandbox` as ``python -I -S -B -u child.py CONFIG_JSON`` from a copy
of this file in the submission's temporary directory (never from the repository), with a
minimal environment (no path to the course, no seed). On Linux it usually runs inside
fresh namespaces whose file system holds only the interpreter, numpy and the working
directory (see :mod:`autograder.sandbox`). Before the submission is loaded it

1. moves the grader's pipes off its standard input and output (requests come on stdin,
   frames go to stdout): descriptor 1 then points at the log like descriptor 2, and 0 at
   the null device, so a ``print`` never reaches the grader and ``input()`` reads nothing;
2. on POSIX levels, lowers its own CPU-time, address-space, file-size, descriptor and
   thread limits (hard limits, so the submission cannot raise them again); at the
   ``"portable"`` level (Windows) it sets none and imports no POSIX-only module;
3. keeps ``ctypes`` from loading at all (numpy would import it, and ctypes reads any
   address in memory without raising an audit event), imports numpy from the one directory
   the grader names, then drops site-packages from ``sys.path`` (so ``course``, ``scipy``
   and the grader are not even findable);
4. installs an audit hook (which Python cannot remove) refusing imports outside numpy and
   the harmless standard library, process creation and signals, sockets, ctypes, the
   Windows API modules, changing the working directory, symbolic links, directories and
   files outside the allowed ones (``site-packages`` excluded), and replacing code objects.
   Everything the hook uses is bound when it is installed, as immutable default arguments
   and C functions (no closure cells, no globals), so a submission that rebinds builtins,
   ``os.path`` or this module's globals, or reads the hook's frame from a refusal's
   traceback, changes nothing. Paths are compared without case where file systems ignore
   it (Windows, macOS); on Windows the kernel's own resolution (``nt._getfinalpathname``:
   links, junctions, short ``~1`` names) decides where a path leads.

Modules numpy itself loaded (``inspect``, ``importlib``, ``pickle``) stay reachable through
``sys.modules``; none of them reaches outside the process. The child then answers requests
one frame per case, so the grader knows exactly which case crashed or hung; each frame
carries the request's random nonce, so frames forged by the submission are recognised.
Everything is judged in the grader.
"""

from __future__ import annotations

import json
import os
import sys
import traceback
import types
from collections.abc import Callable
from typing import Any

# The standard-library modules a submission may import (numpy comes from the assignment):
# computation, text and data, and what those import themselves. Everything else is refused
# with a message that says so: processes, sockets, native code (ctypes, cffi), other
# interpreters (tkinter's Tcl, subinterpreters, code/pdb) and introspection that could reach
# into this script. Modules numpy loaded before the hook stay in ``sys.modules``.
ALLOWED_STDLIB = frozenset("""
    __future__ abc argparse array ast base64 binascii bisect builtins bz2 calendar cmath codecs
    collections colorsys contextlib contextvars copy copyreg csv dataclasses datetime decimal
    difflib dis enum errno fnmatch fractions functools gc genericpath gettext glob graphlib
    hashlib heapq hmac io itertools json keyword linecache locale lzma math numbers ntpath
    opcode operator os pathlib posixpath pprint queue random re reprlib secrets shutil signal
    sre_compile sre_constants sre_parse stat statistics string struct sys tempfile textwrap
    threading time timeit token tokenize traceback types typing unicodedata unittest uuid
    warnings weakref zlib
    _bisect _blake2 _bz2 _compression _csv _decimal _hashlib _heapq _json _locale _lzma _queue
    _random _sha512 _statistics _string _uuid
""".split())
# Audit events refused outright: new processes, signals, network, native code, gc walks,
# tracing, limits, the working directory and symbolic links (both would let a path checked
# here mean another file by the time the kernel opens it). sys._getframe stays allowed
# (collections.namedtuple needs it): the frames it reaches hold nothing to gain, the
# request's nonce included, which lets a submission forge only its own answers.
BLOCKED_EVENTS = frozenset({
    "os.system", "os.exec", "os.posix_spawn", "os.spawn", "os.fork", "os.forkpty",
    "os.kill", "os.killpg", "signal.pthread_kill", "subprocess.Popen", "pty.spawn",
    "gc.get_objects", "gc.get_referrers", "gc.get_referents", "sys.setprofile",
    "sys.settrace", "sys._current_frames", "sys._current_exceptions",
    "os.chroot", "os.setuid", "resource.setrlimit", "resource.prlimit", "os.chdir",
    "os.symlink", "os.startfile",
})
# Prefixes of audit events refused outright: the network, native code, and the Windows API
# (processes, junctions, pipes, the registry).
BLOCKED_PREFIXES = ("socket.", "ctypes.", "_winapi.", "winreg.")
# Audit events with path arguments that must stay inside the working directory.
PATH_EVENTS = frozenset({
    "os.remove", "os.rmdir", "os.mkdir", "os.chmod", "os.chown", "os.truncate", "os.utime",
    "os.link", "os.rename", "shutil.rmtree", "os.chflags", "os.lchflags", "os.setxattr",
    "os.removexattr", "os.mkfifo", "os.mknod",
})
# Audit events with a path argument that must be readable: listing a directory.
LIST_EVENTS = frozenset({"os.listdir", "os.scandir", "os.listxattr", "os.getxattr"})
CODE_ATTRIBUTES = frozenset({"__code__", "__defaults__", "__kwdefaults__", "__globals__"})
# Where file names ignore case by default (NTFS, APFS), so paths are compared without it.
CASELESS_PLATFORMS = ("win32", "darwin")


def main() -> None:
    req, res = _take_pipes()
    config = json.loads(sys.argv[1])
    sys.argv[:] = ["child.py"]
    os.chdir(config["cwd"])  # under the sandbox's chroot the process starts in "/"
    if config["limits"] is not None:
        _limit(config["limits"])
    # None blocks the import (numpy copes without ctypes); typeshed allows only modules.
    sys.modules["ctypes"] = None  # type: ignore[assignment]
    sys.path.append(config["numpy_path"])
    import numpy  # noqa: F401  (loaded before the hook; the submission reuses it)
    import numpy.linalg  # noqa: F401

    protocol = _load_module("_autograder_protocol", config["protocol"])
    sys.path[:] = [p for p in sys.path if p != config["numpy_path"] and "site-packages" not in p]
    stdlib = os.path.realpath(os.path.dirname(os.__file__))
    extensions = []  # Windows keeps the standard library's compiled modules beside it
    nt_paths = None
    if os.name == "nt":
        import nt

        # Private Windows functions that typeshed does not list.
        nt_paths = (nt._getfullpathname, nt._getfinalpathname)  # type: ignore[attr-defined]
        dlls = os.path.join(sys.base_exec_prefix, "DLLs")
        extensions = [os.path.realpath(dlls)] if os.path.isdir(dlls) else []
    sys.addaudithook(make_hook(
        writable=os.path.realpath(config["cwd"]),
        readable=(*(os.path.realpath(p) for p in config["numpy_dirs"]), *extensions, stdlib),
        hidden=tuple(os.path.join(stdlib, d) for d in ("site-packages", "dist-packages")),
        allowed=_allowed_modules(config["allowed"]),
        nt_paths=nt_paths,
    ))
    # Before the submission's first instruction: a start that ends before this frame is the
    # machine's fault (the sandbox, the interpreter), never the submission's.
    protocol.write_frame(res, {"op": "started"})
    try:
        module = _load_module("submission", config["submission"])
    except BaseException as exc:  # noqa: B036  (SystemExit at import is the submission's)
        protocol.write_frame(res, {"op": "load_error", "error": _describe(exc, config)})
        return
    names = config["functions"]
    protocol.write_frame(res, {"op": "ready", "missing": [
        n for n in names if not callable(getattr(module, n, None))]})
    while (request := protocol.read_frame(req)) is not None:
        fn, nonce = getattr(module, request["fn"]), request.pop("nonce")
        most = request.get("most") or [None] * len(request["cases"])
        for i, args in enumerate(request["cases"]):
            protocol.write_frame(res, {**_call(protocol, fn, args, i, config, most[i]),
                                       "nonce": nonce})
        protocol.write_frame(res, {"done": True, "nonce": nonce})


def _take_pipes() -> tuple[int, int]:
    """The grader's request and result pipes, moved off descriptors 0 and 1 (which then read
    the null device and write to the log, as descriptor 2 does); on POSIX every other
    inherited descriptor is closed first."""
    if os.name == "posix":
        os.closerange(3, 1 << 16)
    req, res = os.dup(0), os.dup(1)
    try:
        null = os.open(os.devnull, os.O_RDONLY | getattr(os, "O_BINARY", 0))
    except OSError:  # a jail without a null device: a pipe whose writer is gone reads as empty
        null, writer = os.pipe()
        os.close(writer)
    os.dup2(null, 0)
    os.close(null)
    os.dup2(2, 1)
    return req, res


def _limit(limits: dict[str, float]) -> None:
    import resource  # only asked for on POSIX systems

    cpu, mem = int(limits["cpu_seconds"]), int(limits["memory_mb"]) << 20
    wanted = [(resource.RLIMIT_CPU, cpu), (resource.RLIMIT_AS, mem),
              (resource.RLIMIT_FSIZE, int(limits["file_mb"]) << 20), (resource.RLIMIT_CORE, 0),
              (resource.RLIMIT_NOFILE, 64)]
    if limits.get("tasks"):  # threads and processes of this user (see sandbox.Limits)
        wanted.append((resource.RLIMIT_NPROC, int(limits["tasks"])))
    for limit, value in wanted:
        # CPU: SIGXCPU at the soft limit tells "out of CPU time" even where the grader cannot
        # read the child's CPU time (bubblewrap's processes stand between); SIGKILL 1 s later.
        hard = value + 1 if limit == resource.RLIMIT_CPU else value
        try:
            resource.setrlimit(limit, (value, hard))
        except (ValueError, OSError):  # macOS refuses RLIMIT_AS; the wall clock still holds
            pass
    del sys.modules["resource"]  # a submission importing it again meets the audit hook


def _load_module(name: str, path: str) -> types.ModuleType:
    with open(path, encoding="utf-8") as f:
        code = compile(f.read(), path, "exec")
    module = types.ModuleType(name)
    module.__file__ = path
    sys.modules[name] = module
    exec(code, module.__dict__)
    return module


def _allowed_modules(extra: list[str]) -> frozenset[str]:
    return ALLOWED_STDLIB | frozenset(extra)


# One factory on purpose: the hook and its helpers bind all they use as defaults, here.
def make_hook(writable: str, readable: tuple[str, ...], hidden: tuple[str, ...],  # noqa: C901
              allowed: frozenset[str],
              nt_paths: tuple[Callable[[str], str], Callable[[str], str]] | None = None,
              caseless: bool = sys.platform in CASELESS_PLATFORMS
              ) -> Callable[[str, tuple[Any, ...]], None]:
    """The audit hook. ``writable``: the working directory; ``readable``: the directories a
    submission may read (numpy's and other extra folders first, then the standard library,
    whose ``hidden`` site-packages stay out of reach).

    ``nt_paths``: on Windows, ``nt._getfullpathname`` and ``nt._getfinalpathname``, which
    resolve a path as Windows will open it; elsewhere (None) paths are resolved here one
    component at a time, as the POSIX kernel does. ``caseless``: compare paths without case
    (always with ``nt_paths``), where the file system ignores it.

    The hook and its helpers have no closure cells and read no global or builtin name:
    everything they use is a default argument, bound now, and either immutable (str, tuple,
    frozenset) or a C function. A refusal's traceback shows the hook's frame and so its
    arguments, but nothing in them can be changed, and changing a function's ``__code__`` or
    ``__defaults__`` is itself refused.
    """

    sep = "/" if nt_paths is None else "\\"
    fold = str.lower if caseless or nt_paths is not None else str.__str__

    if nt_paths is None:
        def locate(path, startswith=str.startswith, getcwd=os.getcwd, lstat=os.lstat,
                   readlink=os.readlink, item=tuple.__getitem__, oserror=OSError,
                   refuse=PermissionError):
            """``path`` made absolute with ``.``, ``..`` and symbolic links resolved as the
            POSIX kernel would."""
            if not startswith(path, "/"):
                path = getcwd() + "/" + path
            todo = path.split("/")
            todo.reverse()
            done: list[str] = []
            hops = 0
            while todo:
                part = todo.pop()
                if part == "" or part == ".":
                    continue
                if part == "..":
                    if done:
                        done.pop()
                    continue
                here = "/".join(["", *done, part])
                try:
                    mode = item(lstat(here), 0)  # st_mode, read past any patched attribute
                except oserror:  # not there (yet): nothing to follow
                    mode = 0
                if mode & 0o170000 == 0o120000:  # a symbolic link
                    hops += 1
                    if hops > 40:
                        raise refuse(f"too many symbolic links in {path!r}")
                    target = readlink(here)
                    if startswith(target, "/"):
                        done = []
                    more = target.split("/")
                    more.reverse()
                    todo.extend(more)
                    continue
                done.append(part)
            return "/" + "/".join(done)
    else:  # the Windows variant binds other helpers, so its parameters differ
        def locate(  # type: ignore[misc]
                   path, full=nt_paths[0], final=nt_paths[1], startswith=str.startswith,
                   rpartition=str.rpartition, oserror=OSError, valueerror=ValueError,
                   refuse=PermissionError):
            """``path`` as Windows opens it: made absolute, ``/`` as ``\\``, ``.``, ``..`` and
            trailing dots and spaces dropped (``full``), then links, junctions and short
            ``~1`` names followed to the real, long path (``final``) of the file or, for a
            file not there yet, of its folder."""
            try:
                path = full(path)
            except (oserror, valueerror):  # a NUL character, say
                raise refuse(f"the autograder does not let submissions name {path!r}") from None
            if ":" in path[2:]:  # alternate data streams, \\?\ and \\.\ device paths
                raise refuse(f"the autograder does not let submissions name {path!r}")
            try:
                real = final(path)
            except oserror:  # not there (yet): its folder decides, and open() needs one
                head, _, tail = rpartition(path, "\\")
                try:
                    real = final(head) + "\\" + tail
                except oserror:
                    return path
            if startswith(real, "\\\\?\\UNC\\"):
                return "\\\\" + real[8:]
            return real[4:] if startswith(real, "\\\\?\\") else real

    encoding = sys.getfilesystemencoding()

    def resolve(path, locate=locate, type_=type, str_=str, bytes_=bytes, int_=int,
                decode=bytes.decode, encoding=encoding, refuse=PermissionError):
        """``path`` made absolute and real as the kernel will open it (:func:`locate`); None
        for an open descriptor. Only exact str and bytes are accepted: a str subclass or an
        os.PathLike could show this check one path and open() another.
        """
        kind = type_(path)
        if kind is int_:
            return None
        if kind is bytes_:
            path = decode(path, encoding, "surrogateescape")
        elif kind is not str_:
            raise refuse("the autograder only lets submissions name files by a plain str or "
                         "bytes path")
        return locate(path)

    def within(p, roots, startswith=str.startswith, fold=fold, sep=sep):
        p = fold(p)
        for r in roots:
            if p == r or startswith(p, r + sep):
                return True
        return False

    writable, readable, hidden = (fold(writable), tuple(fold(p) for p in readable),
                                  tuple(fold(p) for p in hidden))
    devnull = fold(resolve(os.devnull))

    def may_read(p, devnull=devnull, writable=writable,
                 extra_dirs=readable[:-1], stdlib=readable[-1:], hidden=hidden, within=within,
                 fold=fold):
        if fold(p) == devnull or within(p, (writable,)) or within(p, extra_dirs):
            return True
        return within(p, stdlib) and not within(p, hidden)

    # One branch per audit-event family; a dispatch table would be a lookup the hook avoids.
    def hook(event, args, resolve=resolve, within=within, may_read=may_read,  # noqa: C901
             writable=(writable,), allowed=allowed, blocked=BLOCKED_EVENTS,
             path_events=PATH_EVENTS, list_events=LIST_EVENTS, code_attributes=CODE_ATTRIBUTES,
             write_flags=os.O_WRONLY | os.O_RDWR | os.O_CREAT | os.O_APPEND | os.O_TRUNC,
             type_=type, str_=str, int_=int, bool_=bool, stat=os.stat, item=tuple.__getitem__,
             startswith=str.startswith, oserror=OSError, refuse=PermissionError,
             refuse_import=ImportError, prefixes=BLOCKED_PREFIXES, devnull=devnull, fold=fold):
        if event == "import":
            name = args[0]
            if type_(name) is not str_ or name.partition(".")[0] not in allowed:
                raise refuse_import(
                    f"importing {name!r} is not allowed here: use numpy and the Python "
                    "standard library only")
        elif event == "open":
            path, mode, flags = args
            p = resolve(path) if path is not None else None
            if p is None:  # an open descriptor
                return
            writing = flags & write_flags != 0
            if mode is not None:
                for c in "wax+":
                    if c in mode:
                        writing = True
            if not (within(p, writable) or fold(p) == devnull) if writing else not may_read(p):
                raise refuse(f"the autograder does not let submissions open {path!r}")
            try:
                is_dir = item(stat(p), 0) & 0o170000 == 0o040000
            except oserror:
                is_dir = False
            if is_dir and not within(p, writable):
                # A descriptor of a directory elsewhere would let dir_fd= paths (which this
                # hook sees relative to the working directory) reach outside it.
                raise refuse(f"the autograder does not let submissions open the directory "
                             f"{path!r}")
        elif event in blocked or startswith(event, prefixes):
            raise refuse(f"the autograder does not let submissions use {event}")
        elif event in path_events or event in list_events:
            for a in args:
                if a is None or type_(a) is int_ or type_(a) is bool_:  # modes, fds, flags
                    continue
                p = resolve(a)
                if p is not None and not (may_read(p) if event in list_events
                                          else within(p, writable)):
                    raise refuse(f"the autograder does not let submissions use {event} "
                                 "outside their working directory")
        elif (event == "object.__setattr__" or event == "object.__delattr__") and (
                args[1] in code_attributes):
            raise refuse("the autograder does not let submissions replace code objects")

    return hook


def _call(protocol: types.ModuleType, fn: Callable[..., object], args: list[Any], i: int,
          config: dict[str, Any], most: int | None) -> dict[str, Any]:
    try:
        value = protocol.encode_value(fn(*protocol.decode_args(args)), most=most)
    except BaseException as exc:  # noqa: B036  (SystemExit, KeyboardInterrupt: the student's)
        return {"case": i, "ok": False, "error": _describe(exc, config)}
    return {"case": i, "ok": True, "value": value}


def _describe(exc: BaseException, config: dict[str, Any]) -> dict[str, Any]:
    """The exception's type, message and the last line of the submission it went through."""
    try:
        message = str(exc)[:300]
    except BaseException:  # noqa: B036  (a hostile __str__)
        message = ""
    where = None
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename == config["submission"]:
            where = {"line": frame.lineno, "code": (frame.line or "")[:120]}
    return {"type": type(exc).__name__[:60], "message": message, "where": where}


if __name__ == "__main__":
    main()
