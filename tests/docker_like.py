"""Run a command as a stock Docker container runs its root process (Gradescope's case).

    python tests/docker_like.py [--bind SRC:DST]... -- COMMAND [ARG]...

Run as root. The command gets what ``docker run`` gives by default, as far as the grader can
tell: a private mount namespace (here with each ``SRC`` bound at ``DST``, e.g. a bundle at
``/autograder``), Docker's 14 default capabilities and no others (so no ``CAP_SYS_ADMIN``), a
seccomp filter that refuses what Docker's default profile refuses without ``CAP_SYS_ADMIN``
(``unshare``, ``clone`` with any namespace flag, ``setns``, ``mount`` and the new mount API,
``pivot_root``; ``clone3`` says ENOSYS so that the C library falls back to ``clone``), and a
private ``TMPDIR`` (mode 0700, as ``mktemp -d`` and systemd's PrivateTmp give). User
namespaces are therefore out of reach, and bubblewrap cannot start.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import os
import sys
import tempfile
from pathlib import Path

CLONE_NEWNS = 0x00020000
MS_BIND, MS_REC, MS_PRIVATE = 0x1000, 0x4000, 0x40000
PR_CAPBSET_DROP = 24
SCMP_CMP_MASKED_EQ = 7
# docker run's default capabilities (moby's oci/caps/defaults.go)
DOCKER_CAPS = frozenset({
    0,   # CAP_CHOWN
    1,   # CAP_DAC_OVERRIDE
    3,   # CAP_FOWNER
    4,   # CAP_FSETID
    5,   # CAP_KILL
    6,   # CAP_SETGID
    7,   # CAP_SETUID
    8,   # CAP_SETPCAP
    10,  # CAP_NET_BIND_SERVICE
    13,  # CAP_NET_RAW
    18,  # CAP_SYS_CHROOT
    27,  # CAP_MKNOD
    29,  # CAP_AUDIT_WRITE
    31,  # CAP_SETFCAP
})
NAMESPACE_FLAGS = 0x7E020000  # CLONE_NEWNS|NEWCGROUP|NEWUTS|NEWIPC|NEWUSER|NEWPID|NEWNET
REFUSED = ("unshare", "setns", "mount", "umount2", "pivot_root", "fsopen", "fsmount",
           "fsconfig", "fspick", "move_mount", "open_tree", "mount_setattr")


class _ArgCmp(ctypes.Structure):
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int),
                ("datum_a", ctypes.c_uint64), ("datum_b", ctypes.c_uint64)]


def _check(rc: int, what: str) -> None:
    if rc != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")


def private_mounts(binds: list[tuple[str, str]]) -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    _check(libc.unshare(CLONE_NEWNS), "unshare(CLONE_NEWNS)")
    _check(libc.mount(None, b"/", None, MS_REC | MS_PRIVATE, None), "mount --make-rprivate /")
    for src, dst in binds:
        os.makedirs(dst, exist_ok=True)  # an empty mount point; the bind hides it
        _check(libc.mount(src.encode(), dst.encode(), None, MS_BIND | MS_REC, None),
               f"mount --bind {src} {dst}")


def docker_capabilities() -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    last = int(Path("/proc/sys/kernel/cap_last_cap").read_text())
    for cap in range(last + 1):
        if cap not in DOCKER_CAPS:
            _check(libc.prctl(PR_CAPBSET_DROP, cap, 0, 0, 0), f"drop capability {cap}")


def docker_seccomp() -> None:
    """Docker's refusals, installed while this process still has CAP_SYS_ADMIN (as Docker
    does it; no ``no_new_privs``)."""
    lib = ctypes.CDLL(ctypes.util.find_library("seccomp") or "libseccomp.so.2")
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int,
                                           ctypes.c_uint, ctypes.POINTER(_ArgCmp)]
    lib.seccomp_load.argtypes = [ctypes.c_void_p]
    lib.seccomp_attr_set.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32]
    ctx = lib.seccomp_init(0x7FFF0000)  # allow
    lib.seccomp_attr_set(ctx, 3, 0)  # SCMP_FLTATR_CTL_NNP off: Docker sets no no_new_privs

    def rule(code: int, name: str, *cmps: _ArgCmp) -> None:
        nr = lib.seccomp_syscall_resolve_name(name.encode())
        if nr < 0:  # not a call of this architecture
            return
        array = (_ArgCmp * len(cmps))(*cmps) if cmps else None
        if lib.seccomp_rule_add_array(ctx, 0x00050000 | code, nr, len(cmps), array) < 0:
            raise OSError(f"seccomp: cannot add the rule for {name}")

    for name in REFUSED:
        rule(errno.EPERM, name)
    rule(errno.ENOSYS, "clone3")
    for bit in range(32):  # clone with any namespace flag: one rule per flag, OR-ed
        if NAMESPACE_FLAGS >> bit & 1:
            rule(errno.EPERM, "clone", _ArgCmp(0, SCMP_CMP_MASKED_EQ, 1 << bit, 1 << bit))
    if lib.seccomp_load(ctx) < 0:
        raise OSError("seccomp_load failed")


def main(argv: list[str]) -> None:
    if "--" not in argv:
        raise SystemExit(__doc__)
    split = argv.index("--")
    options, command = argv[:split], argv[split + 1:]
    binds = []
    while options:
        flag, value, *options = options
        if flag != "--bind" or ":" not in value:
            raise SystemExit(f"unknown option {flag} {value}")
        src, dst = value.split(":", 1)
        binds.append((src, dst))
    private_mounts(binds)
    tmp = tempfile.mkdtemp(prefix="private-tmp-")  # 0700
    os.environ["TMPDIR"] = tmp
    docker_capabilities()
    docker_seccomp()
    os.execvp(command[0], command)


if __name__ == "__main__":
    main(sys.argv[1:])
