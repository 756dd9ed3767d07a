"""A throwaway JupyterHub for `tests/e2e/test_hub.py`, everything under ``COURSE_HUB_ROOT``.

Its parameters come from the environment that `test_hub.hub_server` sets: the root folder,
the ports, the password and the Python whose JupyterLab the users get. Users log in with the
fixed password (shared-password authenticator) and get a single-user JupyterLab as a local
process, each in ``<root>/home/<name>``. The user named by ``COURSE_HUB_NO_PROXY_USER`` gets a
server with the ``jupyter_server_proxy`` extension disabled: a hub where the browser cannot
reach a port of the kernel.
"""

import os
import sys
from pathlib import Path

c = get_config()  # type: ignore[name-defined]  # noqa: F821 (given by JupyterHub)

root = Path(os.environ["COURSE_HUB_ROOT"])
python = os.environ.get("COURSE_HUB_PYTHON", sys.executable)
NO_PROXY_USER = os.environ["COURSE_HUB_NO_PROXY_USER"]

c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = int(os.environ["COURSE_HUB_PORT"])
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = int(os.environ["COURSE_HUB_API_PORT"])
c.JupyterHub.db_url = f"sqlite:///{root / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(root / "jupyterhub_cookie_secret")
c.JupyterHub.pid_file = str(root / "jupyterhub.pid")
c.JupyterHub.cleanup_servers = True
# the pure-Python configurable-http-proxy (a dev extra), so no node/npm is needed; chp.py
# fixes its websocket relay
c.ConfigurableHTTPProxy.command = [python, str(Path(__file__).with_name("chp.py"))]
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{os.environ['COURSE_HUB_PROXY_API_PORT']}"
c.ConfigurableHTTPProxy.pid_file = str(root / "proxy.pid")

c.JupyterHub.authenticator_class = "shared-password"
c.SharedPasswordAuthenticator.user_password = os.environ["COURSE_HUB_PASSWORD"]
c.Authenticator.allow_all = True

c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = str(root / "home" / "{username}")
c.Spawner.cmd = [python, "-m", "jupyterhub.singleuser"]
c.Spawner.default_url = "/lab"
c.Spawner.args = ["--allow-root", "--LabApp.expose_app_in_browser=True", "--LabApp.news_url=",
                  "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"]
c.Spawner.environment = {
    key: os.environ[key] for key in (
        "VTK_DEFAULT_OPENGL_WINDOW", "PYVISTA_OFF_SCREEN", "JUPYTERLAB_SETTINGS_DIR",
        "PYTHONPATH", "XDG_CACHE_HOME") if key in os.environ
}
c.Spawner.http_timeout = 120
c.Spawner.start_timeout = 120


def _per_user(spawner):
    if spawner.user.name == NO_PROXY_USER:
        spawner.args = [*spawner.args,
                        "--ServerApp.jpserver_extensions=jupyter_server_proxy=False"]


c.Spawner.pre_spawn_hook = _per_user
