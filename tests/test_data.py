"""course.data: the shipped sample, the registry, and the mirror / cache / download lookup.

Nothing here touches the internet: downloads are served from a local HTTP server on
127.0.0.1, and "no network" is a closed local port.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import http.server
import logging
import threading
from pathlib import Path

import numpy as np
import pooch
import pytest

from course import data
from course.data import make_sample, registry, store

WALK = "cmu_12_01_walk"
REFUSED = "http://127.0.0.1:9/"  # the discard port: nothing listens, the connection is refused


@pytest.fixture
def empty_dirs(tmp_path, monkeypatch):
    """An empty local mirror and an empty cache; returns (mirror, cache)."""
    mirror, cache = tmp_path / "mirror", tmp_path / "cache"
    mirror.mkdir()
    monkeypatch.setenv("COURSE_DATA_DIR", str(mirror))
    monkeypatch.setenv("COURSE_CACHE_DIR", str(cache))
    return mirror, cache


def serve(directory: Path):
    """A local HTTP server for ``directory``; returns (base URL, stop function)."""
    handler = functools.partial(
        type("Quiet", (http.server.SimpleHTTPRequestHandler,), {"log_message": lambda *a: None}),
        directory=str(directory),
    )
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()

    def stop() -> None:
        server.shutdown()
        server.server_close()

    return f"http://127.0.0.1:{server.server_address[1]}/", stop


def point_url(monkeypatch, name: str, url: str) -> None:
    monkeypatch.setitem(registry.CLIPS, name, dataclasses.replace(registry.CLIPS[name], url=url))


def sha256(file: Path) -> str:
    return hashlib.sha256(file.read_bytes()).hexdigest()


@pytest.fixture
def pooch_records():
    """Every record pooch's logger emits during the test (at any level), and its level is
    checked to be restored afterwards."""
    logger = pooch.get_logger()
    level = logger.level
    records: list[logging.LogRecord] = []
    handler = logging.Handler(logging.DEBUG)
    handler.emit = records.append
    logger.addHandler(handler)
    yield records
    logger.removeHandler(handler)
    assert logger.level == level


def no_network(*args, **kwargs):
    raise AssertionError("no download was expected")


# -- the package's own sample --------------------------------------------------------------


def test_sample_is_regenerated_byte_for_byte():
    shipped = make_sample.SAMPLE_PATH
    assert shipped.read_bytes() == make_sample.wave_bvh_text().encode("utf-8")
    assert shipped.stat().st_size < 200_000


def test_sample_loads_offline(empty_dirs):
    motion = data.load("wave")
    assert data.path("sample") == data.path("wave.bvh") == make_sample.SAMPLE_PATH
    assert (motion.n_frames, motion.fps, motion.n_joints) == (120, pytest.approx(30.0), 24)
    assert sum(not c for c in motion.channels) == 5  # End Sites
    assert "wave" in data.available() and "wave" in data.names()


def test_sample_is_a_plausible_humanoid():
    motion = data.load("wave")
    names = motion.skeleton.names
    positions = motion.forward_kinematics()[0]
    # y up, standing: feet on the ground, head on top, about 1.7 m (30 units of 5.64 cm).
    for toe in ("LeftFoot_end", "RightFoot_end"):
        toe_positions = positions[:, names.index(toe)]
        assert np.abs(toe_positions[:, 1]).max() < 1e-3
        assert np.ptp(toe_positions, axis=0).max() < 1e-3  # planted while the hips sway
    assert 28 < positions[:, names.index("Head_end"), 1].min() < 32
    assert np.ptp(motion.root_positions[:, 0]) == pytest.approx(1.0, abs=0.01)
    # The right hand waves above the head, the left hangs by the hip.
    right = positions[:, names.index("RightHand_end")]
    assert right[:, 1].min() > positions[:, names.index("Head"), 1].max()
    assert np.ptp(right[:, 0]) > 3
    assert positions[:, names.index("LeftHand_end"), 1].max() < 16


def test_sample_loops_seamlessly():
    values = make_sample.wave_channel_values(121)
    assert np.allclose(values[120], values[0], atol=2e-4)
    step = np.abs(np.diff(values, axis=0)).max()
    assert np.abs(values[120] - values[119]).max() <= step  # no jump at the seam


# -- registry ------------------------------------------------------------------------------


def test_acknowledgment():
    assert data.CMU_ACKNOWLEDGMENT == (
        "The data used in this project was obtained from mocap.cs.cmu.edu. "
        "The database was created with funding from NSF EIA-0196217."
    )


def test_registry_matches_the_shared_files(shared_bvh_dir):
    for clip in data.CLIPS.values():
        file = shared_bvh_dir / clip.filename
        assert file.stat().st_size == clip.size, clip.name
        assert sha256(file) == clip.sha256, clip.name
        assert (clip.url is None) == (clip.derived_from is not None)
        if clip.url:
            assert clip.url.startswith("https://raw.githubusercontent.com/")
            assert clip.url.endswith("/" + clip.filename)


def test_unknown_name():
    with pytest.raises(ValueError, match="no clip called 'walk'; known clips: wave, cmu_12_01"):
        data.path("walk")


# -- lookup: mirror, cache, download -------------------------------------------------------


def test_default_mirror_is_beside_the_checkout(monkeypatch):
    monkeypatch.delenv("COURSE_DATA_DIR", raising=False)
    beside = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh"
    assert store.mirror_dir().resolve() == beside.resolve()
    if (beside / "cmu_12_01_walk.bvh").exists():
        assert data.path(WALK) == store.mirror_dir() / "cmu_12_01_walk.bvh"


def test_temporary_mirror(shared_bvh_dir, empty_dirs):
    mirror, cache = empty_dirs
    (mirror / "cmu_12_01_walk.bvh").symlink_to(shared_bvh_dir / "cmu_12_01_walk.bvh")
    assert data.path(WALK) == mirror / "cmu_12_01_walk.bvh"
    motion = data.load(WALK, download=False)
    assert motion.n_frames == 524
    assert data.available() == ["wave", WALK]
    assert not cache.exists()


def test_corrupted_mirror_copy_is_refused(shared_bvh_dir, empty_dirs, monkeypatch):
    mirror, _ = empty_dirs
    # A realistic corruption: an editor or git normalised the line endings.
    raw = (shared_bvh_dir / "cmu_12_01_walk.bvh").read_bytes().replace(b"\r\n", b"\n")
    (mirror / "cmu_12_01_walk.bvh").write_bytes(raw)
    point_url(monkeypatch, WALK, REFUSED + "cmu_12_01_walk.bvh")
    with pytest.raises(data.ChecksumError) as caught:
        data.path(WALK)
    message = str(caught.value)
    assert str(mirror / "cmu_12_01_walk.bvh") in message
    assert hashlib.sha256(raw).hexdigest() in message
    assert data.CLIPS[WALK].sha256 in message


def test_no_network_and_no_copy(empty_dirs, monkeypatch, pooch_records):
    mirror, cache = empty_dirs
    url = REFUSED + "cmu_12_01_walk.bvh"
    point_url(monkeypatch, WALK, url)
    with pytest.raises(data.DataUnavailableError) as caught:
        data.load(WALK)
    message = str(caught.value)
    # The file, its pinned URL, where to save it, where we looked and the two variables.
    for part in ("cmu_12_01_walk.bvh", url, str(cache / "cmu_12_01_walk.bvh"), str(mirror),
                 "COURSE_DATA_DIR", "COURSE_CACHE_DIR", "the download failed"):
        assert part in message
    # The low-level error is chained, not pasted into the message.
    assert caught.value.__cause__ is not None
    for noise in ("Errno", "Max retries", "HTTPConnection", "urllib3", "refused"):
        assert noise not in message
    assert "refused" in str(caught.value.__cause__).lower()
    assert pooch_records == []  # no "Downloading data from ..." before the error
    assert WALK not in data.available()


def test_download_switched_off(empty_dirs, monkeypatch):
    monkeypatch.setattr(store, "_download", no_network)
    with pytest.raises(data.DataUnavailableError, match="downloads are switched off") as caught:
        data.path(WALK, download=False)
    assert data.CLIPS[WALK].url in str(caught.value)
    assert "COURSE_CACHE_DIR" in str(caught.value)


def test_download_into_the_cache(shared_bvh_dir, empty_dirs, monkeypatch, tmp_path,
                                 pooch_records):
    _, cache = empty_dirs
    served = tmp_path / "served"
    served.mkdir()
    (served / "cmu_12_01_walk.bvh").symlink_to(shared_bvh_dir / "cmu_12_01_walk.bvh")
    base, stop = serve(served)
    try:
        point_url(monkeypatch, WALK, base + "cmu_12_01_walk.bvh")
        assert data.path(WALK) == cache / "cmu_12_01_walk.bvh"
    finally:
        stop()
    assert pooch_records == []  # pooch kept quiet
    assert sha256(cache / "cmu_12_01_walk.bvh") == data.CLIPS[WALK].sha256
    # Offline from now on: the cached copy is used.
    point_url(monkeypatch, WALK, REFUSED + "cmu_12_01_walk.bvh")
    assert data.load(WALK).n_frames == 524
    assert WALK in data.available()


def test_corrupted_download_is_refused(shared_bvh_dir, empty_dirs, monkeypatch, tmp_path):
    _, cache = empty_dirs
    served = tmp_path / "served"
    served.mkdir()
    raw = (shared_bvh_dir / "cmu_12_01_walk.bvh").read_bytes()
    (served / "cmu_12_01_walk.bvh").write_bytes(raw[:-1000])  # a truncated transfer
    base, stop = serve(served)
    try:
        point_url(monkeypatch, WALK, base + "cmu_12_01_walk.bvh")
        with pytest.raises(data.ChecksumError, match="failed its checksum"):
            data.path(WALK)
    finally:
        stop()
    assert not (cache / "cmu_12_01_walk.bvh").exists()


def test_corrupted_cache_copy_is_not_used(shared_bvh_dir, empty_dirs, monkeypatch):
    _, cache = empty_dirs
    cache.mkdir()
    (cache / "cmu_12_01_walk.bvh").write_bytes(b"HIERARCHY\n")
    point_url(monkeypatch, WALK, REFUSED + "cmu_12_01_walk.bvh")
    assert WALK not in data.available()
    with pytest.raises(data.DataUnavailableError):
        data.path(WALK)


def test_excerpt_is_cut_from_01_03(shared_bvh_dir, empty_dirs, monkeypatch):
    mirror, cache = empty_dirs
    (mirror / "01_03.bvh").symlink_to(shared_bvh_dir / "01_03.bvh")
    assert data.available() == ["wave", "01_03", "01_03_reach_excerpt"]
    # download=False forbids only the network: cutting from the local source is allowed,
    # as available() promised.
    monkeypatch.setattr(store, "_download", no_network)
    excerpt = data.path("01_03_reach_excerpt", download=False)
    assert excerpt == cache / "01_03_reach_excerpt.bvh"
    assert excerpt.read_bytes() == (shared_bvh_dir / "01_03_reach_excerpt.bvh").read_bytes()
    assert not list(cache.glob("*.part"))
    cut = data.load("01_03_reach_excerpt")
    full = data.load("01_03")
    assert cut.n_frames == 780
    assert np.array_equal(cut.root_positions, full.root_positions[1560:2340])
    assert np.array_equal(cut.local_rotations, full.local_rotations[1560:2340])


def test_excerpt_without_its_source(empty_dirs, monkeypatch):
    point_url(monkeypatch, "01_03", REFUSED + "01_03.bvh")
    with pytest.raises(data.DataUnavailableError, match="reach_excerpt.bvh is cut from 01_03"):
        data.path("01_03_reach_excerpt")
    monkeypatch.setattr(store, "_download", no_network)
    with pytest.raises(data.DataUnavailableError, match="(?s)cut from 01_03.*switched off"):
        data.path("01_03_reach_excerpt", download=False)
    assert "01_03_reach_excerpt" not in data.available()
