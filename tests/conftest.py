"""Shared fixtures: where the real motion-capture clips are."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def shared_bvh_path() -> Path:
    """The local mirror of the sample clips: $COURSE_DATA_DIR or ../shared/data/bvh."""
    env = os.environ.get("COURSE_DATA_DIR")
    return Path(env) if env else REPO.parent / "shared" / "data" / "bvh"


@pytest.fixture(scope="session")
def shared_bvh_dir() -> Path:
    path = shared_bvh_path()
    if not (path / "cmu_12_01_walk.bvh").exists():
        if os.environ.get("CI"):
            pytest.fail(f"CI must have the shared clips at {path}")
        pytest.skip(f"shared motion-capture clips not found at {path}")
    return path


@pytest.fixture
def mujoco_log_elsewhere(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """MuJoCo writes MUJOCO_LOG.TXT into the working folder when a run goes unstable: a test
    that simulates (``pytestmark = pytest.mark.usefixtures("mujoco_log_elsewhere")``) runs in
    its own temporary folder instead of the checkout."""
    monkeypatch.chdir(tmp_path)


@pytest.fixture(scope="module")
def cmu(shared_bvh_dir: Path):
    """The MuJoCo character built from the CMU walk's skeleton, one per test module (a test
    may change its model's options)."""
    from course.bvh import load_bvh
    from course.physics.character import build_model

    return build_model(load_bvh(shared_bvh_dir / "cmu_12_01_walk.bvh").skeleton)
