"""course.viz._backend: which view a student gets, and which thread renders.

In JupyterLab 4.6 with ipykernel 7 widget events arrive on a subshell thread while cells and
the trame server run on the main thread; VTK's OpenGL context must only be used from one of
them. These tests stand in for the kernel with a tornado loop on the test's main thread.
"""

from __future__ import annotations

import os
import threading

import pytest
from tornado.ioloop import IOLoop

from course.viz import _backend


@pytest.fixture
def kernel_loop(monkeypatch):
    loop = IOLoop(make_current=False)
    monkeypatch.setattr(_backend, "_kernel_loop", lambda: loop)
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
        answer.append(_backend.on_gl_thread(render, 21))
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
            _backend.on_gl_thread(lambda: 1 / 0)
        except ZeroDivisionError as err:
            errors.append(err)
        kernel_loop.add_callback(kernel_loop.stop)

    thread = _from_subshell(subshell)
    kernel_loop.start()
    thread.join(5)
    assert len(errors) == 1


def test_on_the_main_thread_or_outside_a_kernel_it_runs_directly(monkeypatch):
    assert _backend.on_gl_thread(lambda a, b: a + b, 1, 2) == 3
    monkeypatch.setattr(_backend, "_kernel_loop", lambda: None)
    out = []
    thread = _from_subshell(lambda: out.append(_backend.on_gl_thread(threading.current_thread)))
    thread.join(5)
    assert out[0].name == "subshell"


def test_a_fast_drag_renders_its_latest_value_not_a_backlog(kernel_loop):
    seen = []
    observer = _backend.latest_on_gl_thread(
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

    observer = _backend.latest_on_gl_thread(broken)

    def subshell():
        observer(1)
        kernel_loop.add_callback(kernel_loop.stop)

    _from_subshell(subshell).join(5)
    kernel_loop.start()
    assert "slider handler failed" in capsys.readouterr().err


def test_the_backend_is_static_outside_a_kernel_and_the_environment_wins(monkeypatch):
    monkeypatch.delenv("PYVISTA_JUPYTER_BACKEND", raising=False)
    assert _backend.jupyter_backend() == "static"  # pytest is no kernel
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "trame")
    assert _backend.jupyter_backend() == "trame"
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "none")
    assert _backend.jupyter_backend() == "static"


def test_trame_is_kept_from_downloading_its_wasm_bundle(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv("VTK_WASM_DIR_OVERRIDE", raising=False)
    _backend.configure_environment()
    wasm = tmp_path / "course-kinematics" / "vtk-wasm"
    assert wasm.is_dir()
    assert os.environ["VTK_WASM_DIR_OVERRIDE"] == str(wasm)
    monkeypatch.setenv("VTK_WASM_DIR_OVERRIDE", "/somewhere/else")  # the user's own wins
    _backend.configure_environment()
    assert os.environ["VTK_WASM_DIR_OVERRIDE"] == "/somewhere/else"


def test_a_kernel_gets_the_browser_rendered_view_unless_the_browser_cannot_reach_it(monkeypatch):
    import sys

    monkeypatch.delenv("PYVISTA_JUPYTER_BACKEND", raising=False)
    monkeypatch.delenv("JUPYTERHUB_SERVICE_PREFIX", raising=False)
    monkeypatch.setattr(_backend, "in_jupyter_kernel", lambda: True)
    assert _backend.jupyter_backend() == "client"
    monkeypatch.setitem(sys.modules, "google.colab", object())  # Colab: no port to reach
    assert _backend.jupyter_backend() == "static"
    monkeypatch.delitem(sys.modules, "google.colab")
    monkeypatch.setenv("JUPYTERHUB_SERVICE_PREFIX", "/user/ada/")
    assert _backend.jupyter_backend() == "client"  # the proxy is installed here
    monkeypatch.setitem(sys.modules, "jupyter_server_proxy", None)  # a hub without it
    assert _backend.jupyter_backend() == "static"


def test_an_unknown_backend_is_named_in_the_error(monkeypatch):
    monkeypatch.setenv("PYVISTA_JUPYTER_BACKEND", "webgl")
    with pytest.raises(ValueError, match="PYVISTA_JUPYTER_BACKEND.*'webgl'"):
        _backend.jupyter_backend()


_VSCODE_MARKERS = ("VSCODE_PID", "VSCODE_CWD", "VSCODE_IPC_HOOK_CLI", "CODESPACES",
                   "REMOTE_CONTAINERS", "SSH_CONNECTION")


@pytest.mark.parametrize("env, backend", [
    ({}, "client"),                                              # JupyterLab on this machine
    ({"VSCODE_PID": "4242"}, "client"),                          # VS Code, local kernel
    ({"VSCODE_PID": "4242", "SSH_CONNECTION": "10.0.0.2 5 10.0.0.3 22"}, "static"),  # Remote-SSH
    ({"VSCODE_CWD": "/w", "REMOTE_CONTAINERS": "true"}, "static"),  # a dev container
    ({"VSCODE_IPC_HOOK_CLI": "/tmp/x.sock", "CODESPACES": "true"}, "static"),  # a Codespace
    ({"SSH_CONNECTION": "10.0.0.2 5 10.0.0.3 22"}, "client"),   # Lab over an SSH tunnel
    ({"JUPYTERHUB_SERVICE_PREFIX": "/user/ada/"}, "client"),     # a hub with the proxy
    ({"PYVISTA_JUPYTER_BACKEND": "server", "VSCODE_PID": "1", "CODESPACES": "true"}, "server"),
])
def test_the_backend_follows_the_environment_markers(monkeypatch, env, backend):
    for name in (*_VSCODE_MARKERS, "PYVISTA_JUPYTER_BACKEND", "JUPYTERHUB_SERVICE_PREFIX"):
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    monkeypatch.setattr(_backend, "in_jupyter_kernel", lambda: True)
    assert _backend.jupyter_backend() == backend
