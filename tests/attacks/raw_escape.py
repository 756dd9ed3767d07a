# ruff: noqa  (an attack run with no audit hook at all, as plain code in the sandbox)
"""Everything a submission that defeated the audit hook (numpy's ``__array_interface__``
writes any address) would try next, by the kernel's own calls. Prints what it reached as
JSON: every entry should be empty or refused."""
import json
import os
import sys
import threading

grader_pid, paths = int(sys.argv[1]), sys.argv[2:]
reached = {"read": [], "listed_root": sorted(os.listdir("/")), "uid": [os.getuid(), os.getgid()]}
for p in paths:
    try:
        with open(p, "rb") as f:
            reached["read"].append([p, f.read(40).decode("latin-1")])
    except OSError:
        pass


def attempt(name, f):
    try:
        reached[name] = repr(f())
    except OSError as exc:
        reached[name] = f"refused: {exc.strerror}"


def chroot_escape():
    os.mkdir("jail")
    os.chroot("jail")
    for _ in range(64):
        os.chdir("..")
    os.chroot(".")
    return os.listdir("/")


attempt("chroot", chroot_escape)
attempt("setuid0", lambda: os.setuid(0))
attempt("fork", os.fork)
attempt("posix_spawn", lambda: os.posix_spawn(sys.executable, [sys.executable, "-c", "0"],
                                              os.environ))
attempt("signal_grader", lambda: os.kill(grader_pid, 0))
attempt("exec_shell", lambda: os.execv("/bin/sh", ["sh", "-c", "id"]))
written = 0
try:
    with open("fill", "wb") as f:
        while written < 1 << 30:
            f.write(b"x" * (1 << 20))
            f.flush()
            written += 1 << 20
except OSError as exc:
    reached["disk_full"] = exc.strerror
reached["disk_written_mb"] = written >> 20
blocks = []
try:
    while len(blocks) < 64:
        blocks.append(bytearray(64 << 20))
except MemoryError:
    pass
reached["memory_mb"] = 64 * len(blocks)
blocks.clear()
threads = []
try:
    while len(threads) < 500:
        t = threading.Thread(target=threading.Event().wait, args=(5,), daemon=True)
        t.start()
        threads.append(t)
except RuntimeError:
    pass
reached["threads"] = len(threads)
for name in ("_socket", "_posixsubprocess", "_ctypes", "_tkinter", "_xxsubinterpreters"):
    try:
        __import__(name)
        reached.setdefault("native_modules", []).append(name)
    except ImportError:
        pass
print(json.dumps(reached))
sys.stdout.flush()
os._exit(0)
