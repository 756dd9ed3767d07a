"""course.viz.backend: which view a student gets, and which thread renders.

In JupyterLab 4.6 with ipykernel 7 widget events arrive on a subshell thread while cells and
the trame server run on the main thread; VTK's OpenGL context must only be used from one of
them. These tests stand in for the kernel with a tornado loop on the test's main thread.
"""

from __future__ import annotations

import os
import socket
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest
from tornado.ioloop import IOLoop

from course.viz import backend


@pytest.fixture
def kernel_loop(monkeypatch):
    loop = IOLoop(make_current=False)
    monkeypatch.setattr(backend, "_kernel_loop", lambda: loop)
    yield loop
    loop.close()


def _from_subshell(fn) -> threading.Thread:
    thread = threading.Thread(target=fn, name="subshell")
    thread.start()
    return thread


def test_a_render_asked_for_on_a_subshell_runs_on_the_main_thread(kernel_loop):
    ran_on, answer = [], []

    def render(x):
        ran_on.append(threading.current_thread())
        return 2 * x

    def subshell():
        answer.append(backend.on_gl_thread(render, 21))
        kernel_loop.add_callback(kernel_loop.stop)

    thread = _from_subshell(subshell)
    kernel_loop.start()  # the main thread's loop serves the request, then is stopped
    thread.join(5)
    assert answer == [42]
    assert ran_on == [threading.main_thread()]


def test_a_failing_render_raises_in_the_thread_that_asked(kernel_loop):
    errors = []

    def subshell():
        try:
            backend.on_gl_thread(lambda: 1 / 0)
        except ZeroDivisionError as err:
            errors.append(err)
        kernel_loop.add_callback(kernel_loop.stop)

    thread = _from_subshell(subshell)
    kernel_loop.start()
    thread.join(5)
    assert len(errors) == 1


def test_on_the_main_thread_or_outside_a_kernel_it_runs_directly(monkeypatch):
    assert backend.on_gl_thread(lambda a, b: a + b, 1, 2) == 3
    monkeypatch.setattr(backend, "_kernel_loop", lambda: None)
    out = []
    thread = _from_subshell(lambda: out.append(backend.on_gl_thread(threading.current_thread)))
    thread.join(5)
    assert out[0].name == "subshell"


def test_soon_waits_for_what_the_loop_has_queued_and_outside_a_kernel_runs_now(
        kernel_loop, monkeypatch):
    order = []
    kernel_loop.add_callback(lambda: order.append("picture sent"))
    backend.soon(lambda: order.append("plot"))
    assert order == [], "in a kernel it waits for the loop"
    kernel_loop.add_callback(kernel_loop.stop)
    kernel_loop.start()
    assert order == ["picture sent", "plot"]
    monkeypatch.setattr(backend, "_kernel_loop", lambda: None)
    backend.soon(lambda: order.append("now"))
    assert order[-1] == "now"


def test_a_fast_drag_renders_its_latest_value_not_a_backlog(kernel_loop):
    seen = []
    observer = backend.latest_on_gl_thread(
        lambda change: seen.append((change, threading.current_thread())))

    def subshell():  # 50 slider events before the main thread gets to any of them
        for value in range(50):
            observer(value)
        kernel_loop.add_callback(kernel_loop.stop)

    thread = _from_subshell(subshell)
    thread.join(5)
    kernel_loop.start()
    assert [v for v, _ in seen] == [49]
    assert seen[0][1] is threading.main_thread()
    observer(7)  # on the main thread (a cell setting .value): at once
    assert seen[-1][0] == 7


def test_an_error_in_a_queued_handler_is_printed_not_lost(kernel_loop, capsys):
    def broken(_change):
        raise RuntimeError("slider handler failed")

    observer = backend.latest_on_gl_thread(broken)

    def subshell():
        observer(1)
        kernel_loop.add_callback(kernel_loop.stop)

    _from_subshell(subshell).join(5)
    kernel_loop.start()
    assert "slider handler failed" in capsys.readouterr().err


def test_the_backend_is_static_outside_a_kernel_and_the_environment_wins(monkeypatch):
    monkeypatch.delenv("PYVISTA_JUPYTER_BACKEND", raising=False)
    assert backend.jupyter_backend() == "static"  # pytest is no kernel
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "trame")
    assert backend.jupyter_backend() == "trame"
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "none")
    assert backend.jupyter_backend() == "static"


def test_trame_is_kept_from_downloading_its_wasm_bundle(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("VTK_WASM_DIR_OVERRIDE", raising=False)
    backend.configure_environment()
    wasm = tmp_path / "course-kinematics" / "vtk-wasm"
    assert wasm.is_dir()
    assert os.environ["VTK_WASM_DIR_OVERRIDE"] == str(wasm)
    monkeypatch.setenv("VTK_WASM_DIR_OVERRIDE", "/somewhere/else")  # the user's own wins
    backend.configure_environment()
    assert os.environ["VTK_WASM_DIR_OVERRIDE"] == "/somewhere/else"


def test_trames_websocket_sends_uncompressed_unless_the_user_asks(monkeypatch):
    """The name is the one wslink reads when its server starts (``reload_settings``)."""
    from wslink.backends import aiohttp as wslink_aiohttp

    monkeypatch.setattr(wslink_aiohttp, "WS_COMPRESS", wslink_aiohttp.WS_COMPRESS)  # restored
    monkeypatch.delenv("WSLINK_WS_COMPRESS", raising=False)
    backend.configure_environment()
    wslink_aiohttp.reload_settings()
    assert wslink_aiohttp.WS_COMPRESS is False
    monkeypatch.setenv("WSLINK_WS_COMPRESS", "1")  # the user's own wins
    backend.configure_environment()
    wslink_aiohttp.reload_settings()
    assert wslink_aiohttp.WS_COMPRESS is True


def test_a_kernel_gets_the_browser_rendered_view_unless_the_browser_cannot_reach_it(monkeypatch):
    import sys

    monkeypatch.delenv("PYVISTA_JUPYTER_BACKEND", raising=False)
    monkeypatch.delenv("JUPYTERHUB_SERVICE_PREFIX", raising=False)
    monkeypatch.setattr(backend, "in_jupyter_kernel", lambda: True)
    assert backend.jupyter_backend() == "client"
    monkeypatch.setitem(sys.modules, "google.colab", object())  # Colab: no port to reach
    assert backend.jupyter_backend() == "static"
    monkeypatch.delitem(sys.modules, "google.colab")
    assert backend.jupyter_backend() == "client"


def test_an_unknown_backend_is_named_in_the_error(monkeypatch):
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "webgl")
    with pytest.raises(ValueError, match="PYVISTA_JUPYTER_BACKEND.*'webgl'"):
        backend.jupyter_backend()


_VSCODE_MARKERS = ("VSCODE_PID", "VSCODE_CWD", "VSCODE_IPC_HOOK_CLI", "CODESPACES",
                   "REMOTE_CONTAINERS", "SSH_CONNECTION")


@pytest.mark.parametrize("env, expected", [
    ({}, "client"),                                              # JupyterLab on this machine
    ({"VSCODE_PID": "4242"}, "client"),                          # VS Code, local kernel
    ({"VSCODE_PID": "4242", "SSH_CONNECTION": "10.0.0.2 5 10.0.0.3 22"}, "static"),  # Remote-SSH
    ({"VSCODE_CWD": "/w", "REMOTE_CONTAINERS": "true"}, "static"),  # a dev container
    ({"VSCODE_IPC_HOOK_CLI": "/tmp/x.sock", "CODESPACES": "true"}, "static"),  # a Codespace
    ({"SSH_CONNECTION": "10.0.0.2 5 10.0.0.3 22"}, "client"),   # Lab over an SSH tunnel
    ({"JUPYTERHUB_SERVICE_PREFIX": "/user/ada/"}, "static"),     # a hub too old to probe
    ({"PYVISTA_JUPYTER_BACKEND": "server", "VSCODE_PID": "1", "CODESPACES": "true"}, "server"),
])
def test_the_backend_follows_the_environment_markers(monkeypatch, env, expected):
    for name in (*_VSCODE_MARKERS, "PYVISTA_JUPYTER_BACKEND", "JUPYTERHUB_SERVICE_PREFIX",
                 "JUPYTERHUB_SERVICE_URL"):
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    monkeypatch.setattr(backend, "in_jupyter_kernel", lambda: True)
    assert backend.jupyter_backend() == expected


# A JupyterHub single-user server, as the kernel's probe sees it (checked on a real hub by
# tests/e2e/test_hub.py): with jupyter-server-proxy, /user/<name>/proxy/<port>/... asks an
# anonymous request to log in (302 to the hub's OAuth page); without it (or for any unknown
# route) the server answers 404 before any login check.
@contextmanager
def _single_user_server(proxy: bool) -> Iterator[tuple[str, list[str]]]:
    """A local HTTP server standing for ``/user/ada/``; yields its service URL and the paths
    it was asked for."""
    asked: list[str] = []

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802 (http.server's name)
            asked.append(self.path)
            if proxy and self.path.startswith("/user/ada/proxy/"):
                self.send_response(302)
                self.send_header("Location", "/hub/api/oauth2/authorize?client_id=ada")
            else:
                self.send_response(404)
            self.send_header("Content-Length", "0")
            self.end_headers()

        def log_message(self, *args) -> None:  # quiet
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/user/ada/", asked
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture
def hub_kernel(monkeypatch):
    """A kernel on a JupyterHub (its environment markers); the probe's cache is emptied."""
    for name in (*_VSCODE_MARKERS, "PYVISTA_JUPYTER_BACKEND", "JUPYTERHUB_SERVICE_URL"):
        monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("JUPYTERHUB_SERVICE_PREFIX", "/user/ada/")
    monkeypatch.setattr(backend, "in_jupyter_kernel", lambda: True)
    backend.hub_serves_proxy.cache_clear()
    yield monkeypatch
    backend.hub_serves_proxy.cache_clear()


def test_a_hub_serving_the_proxy_gets_the_client_view_and_is_asked_once(hub_kernel):
    with _single_user_server(proxy=True) as (url, asked):
        hub_kernel.setenv("JUPYTERHUB_SERVICE_URL", url)
        assert backend.jupyter_backend() == "client"
        assert backend.jupyter_backend() == "client"  # a second view: no second request
    assert asked == ["/user/ada/" + backend.HUB_PROXY_PROBE]


def test_a_hub_without_the_proxy_gets_static_images(hub_kernel):
    with _single_user_server(proxy=False) as (url, asked):
        hub_kernel.setenv("JUPYTERHUB_SERVICE_URL", url)
        assert backend.jupyter_backend() == "static"
    assert len(asked) == 1  # it was asked (a 404), not guessed from installed packages


def test_on_a_hub_without_the_proxy_the_environment_still_wins(hub_kernel):
    with _single_user_server(proxy=False) as (url, asked):
        hub_kernel.setenv("JUPYTERHUB_SERVICE_URL", url)
        hub_kernel.setenv("PYVISTA_JUPYTER_BACKEND", "client")
        assert backend.jupyter_backend() == "client"
    assert asked == []


def test_a_server_that_does_not_answer_means_no_proxy(hub_kernel):
    with socket.socket() as closed:  # a port nobody listens on
        closed.bind(("127.0.0.1", 0))
        port = closed.getsockname()[1]
    hub_kernel.setenv("JUPYTERHUB_SERVICE_URL", f"http://127.0.0.1:{port}/user/ada/")
    assert backend.jupyter_backend() == "static"
    with socket.socket() as silent:  # accepts the connection, never answers: the timeout
        silent.bind(("127.0.0.1", 0))
        silent.listen()
        url = f"http://127.0.0.1:{silent.getsockname()[1]}/user/ada/"
        assert not backend.hub_serves_proxy(url)
    assert not backend.hub_serves_proxy("not a url")
