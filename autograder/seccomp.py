"""The system calls a submission may not make, as a seccomp filter.

The filter is compiled by libseccomp (Debian's ``libseccomp2``, which apt itself depends on),
loaded here through ``ctypes`` in the grader (never in the sandbox), and exported as the
classic BPF program that ``bwrap --seccomp FD`` installs in the child just before the
interpreter starts; at the ``chroot`` level :mod:`autograder.enter_jail` compiles it for the
child's own process id and installs it with ``prctl``. The child and anything it could
start inherit it; nothing can remove it.

What it refuses (``EPERM``; ``ENOSYS`` for ``clone3``, so the C library falls back to
``clone``, whose flags a filter can read):

* new processes: ``fork``, ``vfork``, and ``clone`` without ``CLONE_THREAD`` (threads stay
  allowed), so a submission is exactly one process and its limits are the submission's;
* leaving or reshaping the sandbox: ``mount`` and the new mount API, ``chroot``,
  ``pivot_root``, ``unshare``, ``setns``;
* reaching other processes or the kernel's extensions: ``ptrace``, ``process_vm_readv``/
  ``writev``, ``kcmp``, ``pidfd_getfd``, ``bpf``, ``perf_event_open``, ``keyctl`` and the
  key syscalls, ``userfaultfd``, ``io_uring``, module loading, ``kexec``, ``reboot``, swap,
  clocks, ``open_by_handle_at`` and the like;
* the network: ``socket`` and ``socketpair`` for any family but ``AF_UNIX`` (with
  ``own_pid``, where no network namespace hides the host's abstract unix sockets, no
  ``socket`` at all);
* leaving its session or process group (``setsid``, ``setpgid``) and reaching a process
  through a descriptor (``pidfd_open``, ``pidfd_send_signal``);
* with ``own_pid`` (the ``chroot`` level, where no PID namespace hides the others): any
  signal to another process (``kill``, ``tgkill``, ``rt_sigqueueinfo``,
  ``rt_tgsigqueueinfo`` to a process id other than its own, ``tkill`` at all).

A system call unknown to this machine's architecture is skipped; a call from another
architecture (x32 on x86-64, say) kills the process (libseccomp's default for foreign
architectures).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import os
import socket
from functools import cache

CLONE_THREAD = 0x00010000
REFUSED = (
    "fork", "vfork",
    "mount", "umount", "umount2", "chroot", "pivot_root", "unshare", "setns",
    "fsopen", "fsmount", "fsconfig", "fspick", "move_mount", "open_tree", "mount_setattr",
    "ptrace", "process_vm_readv", "process_vm_writev", "process_madvise", "kcmp",
    "pidfd_getfd", "bpf", "perf_event_open", "keyctl", "add_key", "request_key",
    "userfaultfd", "io_uring_setup", "io_uring_enter", "io_uring_register",
    "init_module", "finit_module", "delete_module", "kexec_load", "kexec_file_load",
    "reboot", "swapon", "swapoff", "acct", "quotactl", "syslog", "vhangup",
    "settimeofday", "clock_settime", "clock_adjtime", "adjtimex", "iopl", "ioperm",
    "modify_ldt", "uselib", "personality", "open_by_handle_at", "name_to_handle_at",
    "lookup_dcookie", "fanotify_init", "nfsservctl",
    "setsid", "setpgid", "pidfd_open", "pidfd_send_signal",
)
# Signals that name their target by process id (argument 0), refused for any id but the
# child's own when it is given; tkill names a thread of any process, so it is refused.
SIGNALLING = ("kill", "tgkill", "rt_sigqueueinfo", "rt_tgsigqueueinfo")
SCMP_ACT_ALLOW = 0x7FFF0000
SCMP_CMP_NE, SCMP_CMP_MASKED_EQ = 1, 7


def _errno(code: int) -> int:
    return 0x00050000 | (code & 0xFFFF)  # SCMP_ACT_ERRNO(code)


class _ArgCmp(ctypes.Structure):
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int),
                ("datum_a", ctypes.c_uint64), ("datum_b", ctypes.c_uint64)]


@cache
def _library() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("seccomp") or "libseccomp.so.2"
    try:
        lib = ctypes.CDLL(name)
    except OSError:
        return None
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_release.argtypes = [ctypes.c_void_p]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int,
                                           ctypes.c_uint, ctypes.POINTER(_ArgCmp)]
    lib.seccomp_export_bpf.argtypes = [ctypes.c_void_p, ctypes.c_int]
    return lib


def available() -> bool:
    """Whether libseccomp can be loaded here (Linux with ``libseccomp2``)."""
    return _library() is not None


@cache
def program(own_pid: int | None = None) -> bytes:
    """The filter as a BPF program (``struct sock_filter`` array), built once; with
    ``own_pid``, signals may reach that process only.

    Raises OSError when libseccomp is missing or refuses a rule.
    """
    lib = _library()
    if lib is None:
        raise OSError("libseccomp is not installed (Debian/Ubuntu: apt-get install libseccomp2)")
    ctx = lib.seccomp_init(SCMP_ACT_ALLOW)
    if not ctx:
        raise OSError("seccomp_init failed")
    try:
        def rule(action: int, name: str, *cmps: _ArgCmp) -> None:
            nr = lib.seccomp_syscall_resolve_name(name.encode())
            if nr < 0:  # not a system call on this architecture
                return
            array = (_ArgCmp * len(cmps))(*cmps) if cmps else None
            rc = lib.seccomp_rule_add_array(ctx, action, nr, len(cmps), array)
            if rc < 0:
                raise OSError(-rc, f"seccomp: cannot add the rule for {name}")

        for name in REFUSED:
            rule(_errno(errno.EPERM), name)
        rule(_errno(errno.ENOSYS), "clone3")
        rule(_errno(errno.EPERM), "clone", _ArgCmp(0, SCMP_CMP_MASKED_EQ, CLONE_THREAD, 0))
        rule(_errno(errno.EPERM), "socketpair", _ArgCmp(0, SCMP_CMP_NE, socket.AF_UNIX, 0))
        if own_pid is None:
            rule(_errno(errno.EPERM), "socket", _ArgCmp(0, SCMP_CMP_NE, socket.AF_UNIX, 0))
        else:  # the host's network namespace: even a unix socket could reach a host service
            rule(_errno(errno.EPERM), "socket")
            rule(_errno(errno.EPERM), "tkill")
            for name in SIGNALLING:
                rule(_errno(errno.EPERM), name, _ArgCmp(0, SCMP_CMP_NE, own_pid, 0))
        fd = os.memfd_create("seccomp")  # a file, not a pipe: the export never blocks
        try:
            rc = lib.seccomp_export_bpf(ctx, fd)
            if rc < 0:
                raise OSError(-rc, "seccomp: cannot export the filter")
            return os.pread(fd, os.fstat(fd).st_size, 0)
        finally:
            os.close(fd)
    finally:
        lib.seccomp_release(ctx)
