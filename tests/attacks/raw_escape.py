# ruff: noqa  (an attack run with no audit hook at all, as plain code in the sandbox)
"""Everything a submission that defeated the audit hook (numpy's ``__array_interface__``
writes any address) would try next, by the kernel's own calls. Arguments: the grader's
process id, a classmate's (running beside it), the classmate's working folder as this
sandbox would name it, then files to read. Prints what it reached as JSON after each step
(the last line is the whole record; the last step, filling the disk, may end it): every
entry should be empty or refused."""
import json
import os
import signal
import sys
import threading

grader_pid, classmate_pid, classmate_work = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
paths = sys.argv[4:]
reached = {"read": [], "listed_root": sorted(os.listdir("/")), "uid": [os.getuid(), os.getgid()]}


def report():
    print(json.dumps(reached), flush=True)


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


def write_outside():
    made = []
    for folder in ("/", "/sandbox", "/sandbox/python", "/sandbox/lib", "/dev", "/dev/shm",
                   "/tmp", os.path.dirname(os.getcwd())):
        try:
            with open(os.path.join(folder, "planted"), "wb") as f:
                f.write(b"x" * 4096)
            made.append(folder)
        except OSError:
            pass
    return made


def reach_classmate():
    found = []
    for look in (lambda: os.listdir(classmate_work), lambda: os.listdir(os.path.dirname(classmate_work)),
                 lambda: open(os.path.join(classmate_work, "submission.py")).read(40)):
        try:
            found.append(look())
        except OSError:
            pass
    return found


attempt("chroot", chroot_escape)
attempt("setuid0", lambda: os.setuid(0))
attempt("fork", os.fork)
attempt("posix_spawn", lambda: os.posix_spawn(sys.executable, [sys.executable, "-c", "0"],
                                              os.environ))
attempt("setsid", os.setsid)
attempt("setpgid", lambda: os.setpgid(0, 0))
attempt("signal_grader", lambda: os.kill(grader_pid, 0))
attempt("signal_classmate", lambda: os.kill(classmate_pid, signal.SIGKILL))
attempt("signal_everyone", lambda: os.kill(-1, signal.SIGKILL))  # every process it may reach
attempt("pidfd_grader", lambda: os.pidfd_open(grader_pid))
attempt("pidfd_classmate", lambda: os.pidfd_open(classmate_pid))
attempt("proc", lambda: os.listdir("/proc"))
attempt("exec_shell", lambda: os.execv("/bin/sh", ["sh", "-c", "id"]))
reached["written_outside"] = write_outside()
reached["classmate"] = reach_classmate()
report()
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
report()
written = 0
try:  # many files of 1 MiB: no one file reaches a per-file limit
    while written < 1 << 30:
        with open(f"fill{written >> 20}", "wb") as f:
            f.write(b"x" * (1 << 20))
        written += 1 << 20
        reached["disk_written_mb"] = written >> 20
        report()
except OSError as exc:
    reached["disk_full"] = exc.strerror
report()
sys.stdout.flush()
os._exit(0)
