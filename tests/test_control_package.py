"""The package course.control: importing it loads nothing heavy (names load on first use,
mujoco only when a MuJoCo model is linearised, scipy never), every public name resolves to
what its submodule defines, and no public name is shadowed by a submodule of the same
name (``linearize`` the function lives in ``linearization``, ``solve_ilqr`` in ``ilqr``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import course.control

REPO = Path(__file__).resolve().parents[1]


def loaded_after(code: str) -> list[str]:
    probe = (f"import sys\n{code}\n"
             "print(*sorted(m for m in ('numpy', 'scipy', 'mujoco') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         cwd=REPO, check=True)
    return out.stdout.split()


def test_importing_the_package_loads_nothing_heavy() -> None:
    assert loaded_after("import course.control") == []
    assert loaded_after("from course.control import lqr_infinite_horizon") == ["numpy"]
    # Every module but the MuJoCo one loads without mujoco or scipy.
    assert loaded_after("import course.control.lqr, course.control.systems, "
                        "course.control.dynamic_programming, course.control.ilqr, "
                        "course.control.policy_gradient, course.control.linearization"
                        ) == ["numpy"]


def test_every_public_name_resolves() -> None:
    for name in course.control.__all__:
        value = getattr(course.control, name)
        assert not isinstance(value, type(sys)), f"{name} is a module, not the function"
    assert set(course.control.__all__) <= set(dir(course.control))
    with pytest.raises(AttributeError, match="has no attribute 'lqr_gain'"):
        course.control.lqr_gain  # noqa: B018


def test_no_submodule_shadows_a_public_name() -> None:
    import course.control.ilqr
    import course.control.linearization  # noqa: F401  (loading it sets the package attribute)

    assert callable(course.control.linearize) and callable(course.control.solve_ilqr)
    submodules = {p.stem for p in (REPO / "course" / "control").glob("*.py")}
    assert not submodules & set(course.control.__all__)
