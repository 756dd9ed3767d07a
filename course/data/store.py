"""Finding a clip on disk: the local mirror, the user cache, or a checked download.

Lookup order for a clip of :data:`~course.data.registry.CLIPS`:

1. the local mirror: ``$COURSE_DATA_DIR``, else ``shared/data/bvh`` beside the checkout
   (where the course's developers and CI keep the clips);
2. the user cache: ``$COURSE_CACHE_DIR``, else ``pooch.os_cache("course-kinematics")``;
3. a download from the clip's pinned URL into the cache, or, for a derived clip, cutting it
   from its source clip (found by the same three steps) into the cache. Cutting is local
   work, so it happens even with ``download=False``, which only forbids the network.

Every file is checked against its SHA-256 before use; a mirror copy that fails the check is an
error (never silently used or replaced).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from .registry import ALIASES, CLIPS, SAMPLES, Clip

SAMPLE_DIR = Path(__file__).resolve().parent / "samples"


class DataError(RuntimeError):
    """A clip could not be provided."""


class DataUnavailableError(DataError):
    """A clip is not on this machine and could not be downloaded."""


class ChecksumError(DataError):
    """A file's SHA-256 is not the pinned one."""


def names() -> list[str]:
    """Every clip name :func:`path` and :func:`~course.data.load` accept (aliases aside)."""
    return [*SAMPLES, *CLIPS]


def available() -> list[str]:
    """The clip names that can be loaded now, without a download (judged by file size; loading
    checks the SHA-256)."""
    return [*SAMPLES, *(name for name, clip in CLIPS.items() if _on_disk(clip))]


def _on_disk(clip: Clip) -> bool:
    """A copy of the clip, or of the clip it is cut from, is on this machine."""
    if _local_copy(clip) is not None:
        return True
    return clip.derived_from is not None and _on_disk(CLIPS[clip.derived_from])


def mirror_dir() -> Path:
    """``$COURSE_DATA_DIR``, else ``shared/data/bvh`` beside the checkout."""
    env = os.environ.get("COURSE_DATA_DIR")
    if env:
        return Path(env)
    import course

    return Path(course.__file__).resolve().parents[2] / "shared" / "data" / "bvh"


def cache_dir() -> Path:
    """``$COURSE_CACHE_DIR``, else the user cache ``pooch.os_cache("course-kinematics")``."""
    env = os.environ.get("COURSE_CACHE_DIR")
    if env:
        return Path(env)
    import pooch

    return Path(pooch.os_cache("course-kinematics"))


def path(name: str, *, download: bool = True) -> Path:
    """The local path of a clip, fetching it into the cache first if needed.

    Parameters
    ----------
    name : str
        One of :func:`names` (a ``.bvh`` suffix is ignored; ``"sample"`` means ``"wave"``).
    download : bool
        Allow a download from the network. A derived clip is still cut from its source when
        that is on this machine (as :func:`available` reports it); only a source that would
        itself need a download is refused.

    Raises
    ------
    ValueError
        If ``name`` is unknown.
    ChecksumError
        If a copy in the local mirror, or a download, does not have the pinned SHA-256.
    DataUnavailableError
        If the clip is not here and cannot be downloaded; the message names the file, its
        pinned URL and where to put it. A failed download is chained as ``__cause__``.
    """
    name = _resolve(name)
    if name in SAMPLES:
        return SAMPLE_DIR / f"{name}.bvh"
    clip = CLIPS[name]
    local = _local_copy(clip, verify=True)
    if local is not None:
        return local
    target = cache_dir() / clip.filename
    if clip.derived_from is not None:
        try:
            source = path(clip.derived_from, download=download)
        except DataUnavailableError as exc:
            raise DataUnavailableError(
                f"{clip.filename} is cut from {clip.derived_from}, which is missing: {exc}"
            ) from exc
        return _derive(clip, source, target)
    if not download:
        raise DataUnavailableError(_how_to_get(clip, target, "downloads are switched off"))
    return _download(clip, target)


def _resolve(name: str) -> str:
    if not isinstance(name, str):
        raise ValueError(f"name: expected a clip name, got {type(name).__name__}")
    key = name.removesuffix(".bvh")
    key = ALIASES.get(key, key)
    if key not in SAMPLES and key not in CLIPS:
        raise ValueError(f"name: no clip called {name!r}; known clips: {', '.join(names())}")
    return key


def _local_copy(clip: Clip, verify: bool = False) -> Path | None:
    """The mirror copy (with ``verify``, a bad one raises), else a good cached copy, else
    None. Without ``verify`` only the sizes are compared (no hashing)."""
    mirror = mirror_dir() / clip.filename
    if mirror.is_file():
        if verify:
            _check(mirror, clip, "local mirror copy")
        elif mirror.stat().st_size != clip.size:
            return None
        return mirror
    cached = cache_dir() / clip.filename
    if cached.is_file() and cached.stat().st_size == clip.size:
        if not verify or _sha256(cached) == clip.sha256:
            return cached
    return None


_hashes: dict[tuple[str, int, int], str] = {}


def _sha256(file: Path) -> str:
    """SHA-256 of a file, remembered while its size and modification time stay the same."""
    stat = file.stat()
    key = (str(file.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _hashes:
        digest = hashlib.sha256()
        with open(file, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
        _hashes[key] = digest.hexdigest()
    return _hashes[key]


def _check(file: Path, clip: Clip, what: str) -> None:
    actual = _sha256(file)
    if actual != clip.sha256:
        raise ChecksumError(
            f"{what} {file} does not match the pinned checksum: SHA-256 {actual} "
            f"({file.stat().st_size} bytes), expected {clip.sha256} ({clip.size} bytes). "
            "Delete or replace it (it may be truncated or converted, e.g. line endings)."
        )


def _derive(clip: Clip, source: Path, target: Path) -> Path:
    """Cut data frames ``clip.frame_range`` of ``source`` into ``target`` (header kept, the
    ``Frames:`` count changed, line endings as in the source) and check the result."""
    if clip.frame_range is None:
        raise ValueError(f"clip {clip.name!r}: no frame_range to cut")
    start, stop = clip.frame_range
    lines = source.read_bytes().splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if line.lstrip().startswith(b"Frames:"))
    ending = lines[at][len(lines[at].rstrip(b"\r\n")) :]
    frames_line = b"Frames: %d" % (stop - start) + ending
    data = lines[at + 2 :][start:stop]
    _write_checked(b"".join([*lines[:at], frames_line, lines[at + 1], *data]), clip, target)
    return target


def _download(clip: Clip, target: Path) -> Path:
    import pooch

    # pooch logs "Downloading data from ..." at INFO level; a notebook should show only our
    # outcome (a clip, or one clean error), so it is kept to warnings for this call.
    logger = pooch.get_logger()
    level = logger.level
    logger.setLevel("WARNING")
    try:
        pooch.retrieve(
            clip.url,
            known_hash=f"sha256:{clip.sha256}",
            fname=target.name,
            path=target.parent,
            downloader=pooch.HTTPDownloader(progressbar=False, timeout=30),
        )
    except ValueError as exc:  # pooch's hash mismatch; the bad download is already removed
        raise ChecksumError(f"download of {clip.url} failed its checksum: {exc}") from exc
    except Exception as exc:  # no network, HTTP error, unwritable cache, ...
        # The low-level error (DNS, refused connection, HTTP status) stays as __cause__.
        raise DataUnavailableError(
            _how_to_get(clip, target, f"the download failed ({type(exc).__name__})")
        ) from exc
    finally:
        logger.setLevel(level)
    return target


def _write_checked(content: bytes, clip: Clip, target: Path) -> None:
    actual = hashlib.sha256(content).hexdigest()
    if actual != clip.sha256:
        raise ChecksumError(
            f"{clip.filename} cut from {clip.derived_from} has SHA-256 {actual}, "
            f"expected {clip.sha256}: the source file is not the pinned one"
        )
    target.parent.mkdir(parents=True, exist_ok=True)
    partial = target.with_name(target.name + ".part")
    partial.write_bytes(content)
    os.replace(partial, target)  # atomic: never a half-written clip in the cache


def _how_to_get(clip: Clip, target: Path, why: str) -> str:
    return (
        f"{clip.filename} is not on this machine and {why}.\n"
        f"  Looked in the local mirror {mirror_dir()} (COURSE_DATA_DIR) and the cache "
        f"{target.parent} (COURSE_CACHE_DIR).\n"
        f"  To get it: download {clip.url}\n"
        f"  and save it as {target}, or put it in a folder and set COURSE_DATA_DIR to that "
        "folder."
    )
