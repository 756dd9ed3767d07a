"""The kernel boundary of the bubblewrap sandbox, attacked as if the audit hook were already
defeated: raw code in the sandbox's place, and the seccomp filter on its own. Each attack
records what it reached; the tests assert it reached nothing."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from test_autograder_fixtures import REPO

from autograder import jail, seccomp
from autograder.sandbox import INSIDE, SANDBOX_UID, Limits, Sandbox, isolation, remove_tree

ATTACK = Path(__file__).parent / "attacks" / "raw_escape.py"
SLEEPER = "import time\ntime.sleep(60)\n"
KERNEL_LEVELS = ["bubblewrap", "chroot"]
OVERSHOOT_MB = 64  # the most the chroot level's disk watch may let through (measured: < 32)
RAW_LIMITS = {"memory_mb": 512, "cpu_seconds": 30, "file_mb": 8, "tasks": 32}


def needs(level: str) -> None:
    """Skip unless this machine gives ``level``."""
    if level == "bubblewrap" and isolation() != "bubblewrap":
        pytest.skip("no bubblewrap sandbox on this machine")
    if level == "chroot" and (os.geteuid() != 0 or not seccomp.available()):
        pytest.skip("the chroot level needs a root grader and libseccomp")


def raw(box: Sandbox, args: list[str]) -> subprocess.Popen[bytes]:
    """The submission's file run as the program, in the child's place: no audit hook."""
    config = {"cwd": f"{INSIDE}/work", "limits": RAW_LIMITS}
    return box.spawn(config, ["-I", "-S", "submission.py", *args], stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE)


def processes_of(uid: int) -> list[int]:
    """The processes the user ``uid`` runs now."""
    found = []
    for entry in os.scandir("/proc"):
        if entry.name.isdigit():
            try:
                if entry.stat().st_uid == uid:
                    found.append(int(entry.name))
            except OSError:
                pass
    return found


@pytest.mark.parametrize("level", KERNEL_LEVELS)
def test_with_the_hook_defeated_the_kernel_gives_nothing(tmp_path, level, monkeypatch):
    """The escapes of the security review, run as plain Python with no audit hook while a
    classmate's submission runs beside it: no host file, no chroot escape, no process, no
    signal or pidfd to the grader or the classmate, no other folder, no writable place but
    its own, the disk and memory limits hold, no native module, and nothing left running."""
    needs(level)
    # user ids no other test leases: "nothing left running" must not see a classmate test's
    monkeypatch.setenv(jail.UIDS_ENV, "61950-61999")
    secret = tmp_path / "grades.csv"
    secret.write_text("alice,24\n")
    targets = [str(REPO / "tests/fixtures/a1/reference.py"), "/etc/shadow", "/etc/passwd",
               "/proc/1/cmdline", f"/proc/{os.getpid()}/cmdline", "/proc/self/status",
               str(secret), "/root/.bashrc", sys.executable, "/usr/bin/python3"]
    limits = Limits(memory_mb=512, disk_mb=8)
    with Sandbox(SLEEPER, [], limits, frozenset(), level=level) as mate, \
            Sandbox(ATTACK.read_text(), [], limits, frozenset(), level=level) as box:
        classmate = raw(mate, [])
        # where the classmate's folder is as this sandbox could name it: at bubblewrap a
        # tmpfs of another mount namespace, so its host path
        mate_work = (f"{INSIDE}/work/{mate.work.name}" if level == "chroot"
                     else str(mate.root / "work"))
        proc = raw(box, [str(os.getpid()), str(classmate.pid), mate_work, *targets])
        out, err = proc.communicate(timeout=120)
        assert classmate.poll() is None, "the classmate was killed"
        leased = box._lease.uid if box._lease else None
        if level == "bubblewrap":  # the raw child is not the box's to stop
            os.killpg(classmate.pid, signal.SIGKILL)
    classmate.wait(timeout=10)  # at the chroot level, ended with every process of its user
    reached = json.loads(out.splitlines()[-1])
    assert reached["read"] == []
    assert reached["listed_root"] == ["dev", "lib64", "sandbox"]
    assert reached["written_outside"] == [] and reached["classmate"] == []
    assert reached["uid"][0] == reached["uid"][1] != 0
    for attempt in ("chroot", "fork", "posix_spawn", "setsid", "setpgid", "pidfd_grader",
                    "pidfd_classmate"):
        assert reached[attempt] == "refused: Operation not permitted", attempt
    assert reached["exec_shell"] == "refused: No such file or directory"
    assert reached["proc"] == "refused: No such file or directory"
    assert reached["memory_mb"] <= limits.memory_mb
    assert reached["threads"] < 32  # RLIMIT_NPROC: its own user's (namespace's) tasks
    assert "native_modules" not in reached
    if level == "bubblewrap":
        assert reached["uid"] == [SANDBOX_UID, SANDBOX_UID]
        assert reached["setuid0"] == "refused: Invalid argument"  # no uid 0 in its namespace
        assert reached["signal_grader"] == "refused: No such process"  # not even visible
        assert reached["disk_full"] == "No space left on device"
        assert reached["disk_written_mb"] <= limits.disk_mb
    else:
        assert reached["uid"][0] == leased and leased in jail.uid_range()
        assert reached["setuid0"] == "refused: Operation not permitted"
        for attempt in ("signal_grader", "signal_classmate", "signal_everyone"):
            assert reached[attempt] == "refused: Operation not permitted", attempt
        # no tmpfs without mounts: the disk watch stopped it, within milliseconds of its
        # limit (writing at memory speed, that is some MiB past it; docs/sandbox.md). It
        # reports each 1 MiB file after writing it: stopped at once, the last report is one
        # file short of the limit.
        assert "disk_full" not in reached and proc.returncode == -signal.SIGKILL
        assert limits.disk_mb - 1 <= reached["disk_written_mb"] <= limits.disk_mb + OVERSHOOT_MB
        assert processes_of(leased) == []
        assert not mate.work.exists() and not box.work.exists()


FILTERED = ["fork", "vfork", "mount", "umount2", "chroot", "pivot_root", "unshare", "setns",
            "ptrace", "process_vm_readv", "process_vm_writev", "bpf", "perf_event_open",
            "keyctl", "add_key", "userfaultfd", "io_uring_setup", "init_module", "kexec_load",
            "open_by_handle_at", "fsopen", "move_mount", "setsid", "setpgid", "pidfd_open",
            "pidfd_send_signal"]


@pytest.mark.skipif(not seccomp.available() or sys.platform != "linux",
                    reason="no libseccomp on this machine")
@pytest.mark.parametrize("level", KERNEL_LEVELS)
def test_the_seccomp_filter_refuses_every_listed_call_and_keeps_threads(level):
    """The filter installed in a throwaway process (native calls through ctypes, as an
    attacker with code execution would make them): every listed call is refused, sockets
    too but AF_UNIX, a non-thread clone too, and clone3 says ENOSYS so threads still start.
    The chroot level's filter, built for the process's own id, also refuses every socket
    and any signal but to itself."""
    probe = textwrap.dedent(f"""
        import ctypes, json, os, signal, socket, threading
        from autograder import seccomp
        libc = ctypes.CDLL(None, use_errno=True)
        lib = ctypes.CDLL("libseccomp.so.2")
        nr = lambda n: lib.seccomp_syscall_resolve_name(n.encode())
        me = os.getpid()
        prog = seccomp.program(own_pid=me if {level == "chroot"} else None)
        class Fprog(ctypes.Structure):
            _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_char_p)]
        fprog = Fprog(len(prog) // 8, prog)
        assert libc.prctl(38, 1, 0, 0, 0) == 0  # PR_SET_NO_NEW_PRIVS
        assert libc.prctl(22, 2, ctypes.byref(fprog), 0, 0) == 0  # SECCOMP_MODE_FILTER
        def errno_of(*args):
            ctypes.set_errno(0)
            rc = libc.syscall(*args)
            return ctypes.get_errno() if rc == -1 else "allowed"
        found = {{n: errno_of(nr(n), 0, 0, 0, 0, 0) for n in {FILTERED!r}}}
        found["clone"] = errno_of(nr("clone"), 17, 0, 0, 0, 0)  # SIGCHLD: a new process
        found["clone3"] = errno_of(nr("clone3"), 0, 0)
        found["socket_inet"] = errno_of(nr("socket"), socket.AF_INET, socket.SOCK_STREAM, 0)
        found["socket_unix"] = errno_of(nr("socket"), socket.AF_UNIX, socket.SOCK_STREAM, 0)
        pair = (ctypes.c_int * 2)()
        found["socketpair_unix"] = errno_of(nr("socketpair"), socket.AF_UNIX,
                                            socket.SOCK_STREAM, 0, ctypes.byref(pair))
        found["kill_self"] = errno_of(nr("kill"), me, 0)
        found["kill_parent"] = errno_of(nr("kill"), os.getppid(), 0)
        found["kill_group"] = errno_of(nr("kill"), 0, 0)
        found["tgkill_self"] = errno_of(nr("tgkill"), me, threading.get_native_id(), 0)
        found["tkill"] = errno_of(nr("tkill"), threading.get_native_id(), 0)
        t = threading.Thread(target=lambda: None); t.start(); t.join()
        found["thread"] = "started"
        print(json.dumps(found))
    """)
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         timeout=60, cwd=REPO)
    assert out.returncode == 0, out.stderr
    found = json.loads(out.stdout)
    for name in [*FILTERED, "clone", "socket_inet"]:
        assert found[name] == errno.EPERM, name
    assert found["clone3"] == errno.ENOSYS and found["thread"] == "started"
    assert found["socketpair_unix"] == found["kill_self"] == found["tgkill_self"] == "allowed"
    refused_here = ("socket_unix", "kill_parent", "kill_group", "tkill")
    if level == "chroot":
        assert all(found[n] == errno.EPERM for n in refused_here), found
    else:
        assert all(found[n] == "allowed" for n in refused_here), found


def test_a_deep_tree_with_closed_folders_is_removed(tmp_path):
    """What a submission may leave in its folder below bubblewrap (whose tmpfs vanishes): 3000
    levels (paths far past PATH_MAX, beyond any recursion) and a folder closed to everyone."""
    top = tmp_path / "work"
    top.mkdir()
    fd = os.open(top, os.O_RDONLY)
    for level in range(3000):
        os.mkdir("d", dir_fd=fd)
        inner = os.open("d", os.O_RDONLY, dir_fd=fd)
        if level % 500 == 0:
            os.close(os.open("f", os.O_WRONLY | os.O_CREAT, dir_fd=inner))
        os.close(fd)
        fd = inner
    os.mkdir("closed", dir_fd=fd)
    os.chmod("closed", 0, dir_fd=fd)
    os.close(fd)
    remove_tree(top)
    assert not top.exists()
