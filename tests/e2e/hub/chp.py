"""The hub's proxy: the pure-Python ``configurable-http-proxy`` (PyPI, no node needed), with
its websocket relay fixed for what the course's views send.

Version 0.4.0 relays a binary message from the browser as a text frame (``on_message``
forwards it without ``binary=True``): vtk.js's view talks msgpack to the kernel's trame
server, which then never answers, and the view stays on "Loading...". It also does not echo
the subprotocol the server picked (JupyterLab's kernel socket then fails once and reconnects
without it). Both are patched here; node's configurable-http-proxy needs neither.
"""

from __future__ import annotations

from typing import Any

from configurable_http_proxy import handlers
from configurable_http_proxy.cli import main


def _on_message(self: Any, message: str | bytes) -> None:
    if self.ws_client:
        prefix = self.target["prefix"] if self.target else ""
        if prefix:
            self.proxy.update_last_activity(prefix)
        self.ws_client.write_message(message, binary=isinstance(message, bytes))


def _select_subprotocol(self: Any, subprotocols: list[str]) -> str | None:
    # the client to the target connects first, with the browser's headers: its choice stands
    return getattr(self.ws_client, "selected_subprotocol", None)


handlers.ProxyHandler.on_message = _on_message
handlers.ProxyHandler.select_subprotocol = _select_subprotocol

if __name__ == "__main__":
    main()
