"""The sandboxed side: load one submission, call its functions on inputs, report results.

Run by :mod:`autograder.sandbox` as ``python -I -S -B -u child.py CONFIG_JSON`` in a fresh
temporary directory with a minimal environment (no path to the course, no seed). Before
the submission is loaded it

1. lowers its own CPU-time, address-space and file-size limits (soft = hard, so the
   submission cannot raise them again);
2. imports numpy from the one directory the grader names, then drops site-packages from
   ``sys.path`` (so ``course``, ``scipy`` and the grader are not even findable);
3. installs an audit hook (which Python cannot remove) refusing imports outside numpy and
   the harmless standard library, process creation and signals, sockets, ctypes, files
   outside the allowed directories, and tampering with the hook itself.

It then answers requests on a dedicated pipe (never stdout), one frame per case, so the
grader knows exactly which case crashed or hung; each frame carries the request's random
nonce, so frames forged by the submission are recognised. Everything is judged in the
grader.
"""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import traceback

# Standard-library modules a submission may not load: processes, signals, sockets, native
# code, and introspection that could reach into this script.
BLOCKED_STDLIB = frozenset({
    "subprocess", "_posixsubprocess", "multiprocessing", "_multiprocessing", "concurrent",
    "socket", "_socket", "ssl", "_ssl", "http", "urllib", "ftplib", "smtplib", "asyncio",
    "ctypes", "_ctypes", "pty", "signal", "resource", "gc", "inspect", "importlib",
    "pickle", "_pickle", "marshal", "shutil",
})
# Audit events refused outright: new processes, signals, network, native code, gc walks.
BLOCKED_EVENTS = frozenset({
    "os.system", "os.exec", "os.posix_spawn", "os.spawn", "os.fork", "os.forkpty",
    "os.kill", "os.killpg", "signal.pthread_kill", "subprocess.Popen", "pty.spawn",
    "ctypes.dlopen", "ctypes.dlsym", "ctypes.cdata", "ctypes.call_function",
    "ctypes.addressof", "gc.get_objects", "gc.get_referrers", "gc.get_referents",
    "sys.setprofile", "sys.settrace", "sys._getframe", "os.chroot", "os.setuid",
})
# Events with one path argument that must stay inside the sandbox directory.
PATH_EVENTS = frozenset({
    "os.listdir", "os.scandir", "os.chdir", "os.remove", "os.rmdir", "os.mkdir", "os.chmod",
    "os.chown", "os.truncate", "os.utime", "os.link", "os.symlink", "os.rename", "shutil.rmtree",
    "os.chflags", "os.lchflags", "os.setxattr", "os.removexattr", "os.listxattr", "os.getxattr",
})


def main() -> None:
    config = json.loads(sys.argv[1])
    del sys.argv[1:]
    req, res = config["req_fd"], config["res_fd"]
    _limit(config)
    sys.path.append(config["numpy_path"])
    import numpy  # noqa: F401  (loaded before the hook; the submission reuses it)
    import numpy.linalg  # noqa: F401

    protocol = _load_protocol()
    sys.path[:] = [p for p in sys.path if p != config["numpy_path"] and "site-packages" not in p]
    sandbox = os.path.realpath(os.getcwd())
    readable = (sandbox, os.path.dirname(os.path.realpath(os.__file__)),
                *(os.path.realpath(p) for p in config["numpy_dirs"]))
    _install_hook(sandbox, readable, _allowed_modules(config["allowed"]))

    try:
        module = _load(config["submission"])
    except BaseException as exc:  # noqa: B036  (SystemExit at import is the submission's)
        protocol.write_frame(res, {"op": "load_error", "error": _describe(exc, config)})
        return
    names = config["functions"]
    protocol.write_frame(res, {"op": "ready", "missing": [
        n for n in names if not callable(getattr(module, n, None))]})
    while (request := protocol.read_frame(req)) is not None:
        fn, nonce = getattr(module, request["fn"]), request.pop("nonce")
        for i, args in enumerate(request["cases"]):
            protocol.write_frame(res, {**_call(protocol, fn, args, i, config), "nonce": nonce})
        protocol.write_frame(res, {"done": True, "nonce": nonce})


def _limit(config: dict) -> None:
    import resource

    cpu, mem = int(config["cpu_seconds"]), int(config["memory_mb"]) << 20
    for limit, value in ((resource.RLIMIT_CPU, cpu), (resource.RLIMIT_AS, mem),
                         (resource.RLIMIT_FSIZE, 16 << 20), (resource.RLIMIT_CORE, 0)):
        try:
            resource.setrlimit(limit, (value, value))
        except (ValueError, OSError):  # macOS refuses RLIMIT_AS; the wall clock still holds
            pass


def _load_protocol():
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "protocol.py")
    spec = importlib.util.spec_from_file_location("_autograder_protocol", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _allowed_modules(extra: list[str]) -> frozenset[str]:
    return frozenset(sys.stdlib_module_names - BLOCKED_STDLIB) | frozenset(extra)


def _install_hook(sandbox: str, readable: tuple[str, ...], allowed: frozenset[str]) -> None:
    realpath, fspath, sep = os.path.realpath, os.fsdecode, os.sep

    def inside(path, roots) -> bool:
        if isinstance(path, int):  # an already open descriptor
            return True
        p = realpath(fspath(path))
        return any(p == r or p.startswith(r + sep) for r in roots) or p == "/dev/null"

    def hook(event: str, args: tuple) -> None:
        if event == "import":
            top = str(args[0]).partition(".")[0]
            if top not in allowed:
                raise ImportError(
                    f"importing {args[0]!r} is not allowed here: use numpy and the "
                    "Python standard library only")
        elif event == "open":
            path, mode, flags = args
            writing = (mode is not None and any(c in mode for c in "wax+")) or (
                mode is None and flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT))
            if path is not None and not inside(path, (sandbox,) if writing else readable):
                raise PermissionError(f"the autograder does not let submissions open {path!r}")
        elif event in BLOCKED_EVENTS or event.startswith("socket."):
            raise PermissionError(f"the autograder does not let submissions use {event}")
        elif event in PATH_EVENTS:
            paths = [a for a in args[:2] if isinstance(a, (str, bytes, os.PathLike))]
            if not all(inside(p, (sandbox,)) for p in paths):
                raise PermissionError(f"the autograder does not let submissions use {event} "
                                      "outside their working directory")
        elif event == "object.__setattr__" and args[0] is hook:
            raise PermissionError("the autograder's guard cannot be modified")

    sys.addaudithook(hook)


def _load(path: str):
    spec = importlib.util.spec_from_file_location("submission", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _call(protocol, fn, args: list, i: int, config: dict) -> dict:
    try:
        value = protocol.encode_value(fn(*protocol.decode_args(args)))
    except BaseException as exc:  # noqa: B036  (SystemExit, KeyboardInterrupt: the student's)
        return {"case": i, "ok": False, "error": _describe(exc, config)}
    return {"case": i, "ok": True, "value": value}


def _describe(exc: BaseException, config: dict) -> dict:
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
