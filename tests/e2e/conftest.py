"""Browser tests run only when asked for by path (`make e2e` runs `pytest tests/e2e`): the
plain `pytest` / `make test` run skips this folder, notebook included."""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).resolve().parent


def _asked_for(config) -> bool:
    for arg in config.args:
        path = Path(arg.split("::")[0]).resolve()
        if path == HERE or HERE in path.parents:
            return True
    return False


def pytest_ignore_collect(collection_path: Path, config) -> bool | None:
    if not _asked_for(config) and (collection_path == HERE or HERE in collection_path.parents):
        return True
    return None
