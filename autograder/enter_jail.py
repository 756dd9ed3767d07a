"""Enter a submission's jail as its own user: the first program of the ``chroot`` level.

The grader runs this file, as root, with its own interpreter (``python -I -S -B``), in one of
two forms::

    enter_jail.py run UID JAIL CWD -- PROGRAM ARG...
    enter_jail.py reap UID

``run`` turns this fresh process into the submission's: it compiles the seccomp filter of
:mod:`autograder.seccomp` for its own process id (libseccomp is only reachable before the
``chroot``), enters ``JAIL`` with ``chroot`` and ``CWD`` with ``chdir``, drops every group
and becomes ``UID`` (real, effective and saved: the kernel then clears every capability),
sets ``no_new_privs``, installs the filter, and replaces itself with ``PROGRAM`` (a path
inside the jail). ``reap`` becomes ``UID`` and sends SIGKILL to every process of that user
(``kill(-1)`` reaches exactly those), which ends whatever a submission left running.

It is a separate program, not a ``preexec_fn``, because the grader has threads (forking a
threaded process and running Python in the child can deadlock); it imports nothing of the
package but ``seccomp.py``, loaded by path. Any failure is one line on standard error and
exit status 125, before the submission's code could run.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from importlib.util import module_from_spec, spec_from_file_location
from pathlib import Path

PR_SET_NO_NEW_PRIVS = 38
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2
FAILED = 125


class _Fprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_char_p)]


def become(uid: int) -> None:
    """Drop every group and every capability: from here on this process is ``uid`` alone."""
    os.setgroups([])
    os.setresgid(uid, uid, uid)
    os.setresuid(uid, uid, uid)


def run(uid: int, jail: str, cwd: str, argv: list[str]) -> None:
    spec = spec_from_file_location("_seccomp", Path(__file__).with_name("seccomp.py"))
    assert spec is not None and spec.loader is not None
    seccomp = module_from_spec(spec)
    spec.loader.exec_module(seccomp)
    program = seccomp.program(own_pid=os.getpid())
    libc = ctypes.CDLL(None, use_errno=True)
    os.chroot(jail)
    os.chdir(cwd)
    os.umask(0o077)
    become(uid)
    fprog = _Fprog(len(program) // 8, program)
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_NO_NEW_PRIVS)")
    if libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.byref(fprog), 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_SECCOMP)")
    os.execv(argv[0], argv)


def reap(uid: int) -> None:
    become(uid)
    try:
        os.kill(-1, signal.SIGKILL)  # every process of uid but this one
    except ProcessLookupError:  # none was left
        pass


def main(args: list[str]) -> None:
    try:
        if args[:1] == ["reap"] and len(args) == 2:
            reap(int(args[1]))
        elif args[:1] == ["run"] and len(args) > 5 and args[4] == "--":
            run(int(args[1]), args[2], args[3], args[5:])
        else:
            raise ValueError(f"usage: {__doc__.splitlines()[4].strip()}")
    except (OSError, ValueError) as exc:
        print(f"enter_jail: {exc}", file=sys.stderr)
        sys.exit(FAILED)


if __name__ == "__main__":
    main(sys.argv[1:])
