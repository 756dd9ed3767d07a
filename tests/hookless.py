"""The grader as if every submission had already removed its audit hook.

The hook is a courtesy (it tells a student "numpy and the standard library only"); a
submission that writes memory through numpy's ``__array_interface__`` can remove it, so the
boundary is the kernel's alone. To test that, this grader's child never installs the hook:
:func:`install` points the sandbox at a copy of ``child.py`` without it. As a program,
``python tests/hookless.py ARGS...`` is ``python -m autograder ARGS...`` with that child
(and, with ``$HOOKLESS_LEASES``, a record of the user ids it leased).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

from autograder import jail, runtime
from autograder.cli import main

HOOK = "    sys.addaudithook(make_hook("


def install(folder: Path) -> None:
    """Stage and start every child from a hookless copy of the child's files in ``folder``."""
    child, protocol = runtime.CHILD_FILES
    text = child.read_text()
    assert text.count(HOOK) == 1, "child.py no longer installs its hook this way"
    (folder / child.name).write_text(text.replace(HOOK, "    (lambda hook: None)(make_hook("))
    (folder / protocol.name).write_bytes(protocol.read_bytes())
    runtime.CHILD_FILES = (folder / child.name, folder / protocol.name)
    runtime.staged.cache_clear()


def record_leases(path: Path) -> None:
    """Append each user id the chroot level leases to ``path`` (what a test then checks has
    no process left)."""
    lease = jail.Lease.__init__

    def leased(self: jail.Lease) -> None:
        lease(self)
        with path.open("a") as f:
            f.write(f"{self.uid}\n")

    jail.Lease.__init__ = leased  # type: ignore[method-assign]


if __name__ == "__main__":
    install(Path(tempfile.mkdtemp(prefix="hookless-")))
    if os.environ.get("HOOKLESS_LEASES"):
        record_leases(Path(os.environ["HOOKLESS_LEASES"]))
    sys.exit(main(sys.argv[1:]))
