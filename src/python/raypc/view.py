"""The browser UI of a dataset in a notebook, linked both ways: the server this process starts for
it, and the view that reads and sets the state the UI shows through the server's /api/link."""
from __future__ import annotations

import atexit
import json
import os
import threading
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Any, Callable, Optional, Union

from . import _raypc
from ._raypc import Error
from .dataset import Dataset
from .state import State

_servers: dict = {}  # (dataset dir, host, port) -> _raypc.Server, reused by show()


def _inside_package(name: str, needs: str = "") -> Optional[str]:
    """The package's copy of the UI (``web``) or of the example states (``examples``), which an
    installed package carries (setup.py puts them there); None in the build tree, where the server
    finds them in the source tree as the executable does."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), name)
    return path if os.path.isdir(path) and (not needs or os.path.isfile(os.path.join(path, needs))) else None


@atexit.register
def _stop_servers() -> None:
    """Stops the servers show() started before the interpreter goes away under their threads."""
    for server in list(_servers.values()):
        server.stop()
    _servers.clear()


class View:
    """The browser UI of a dataset served by this process (:func:`raypc.show`), or by any ``raypc
    serve`` at ``url``. ``view.state`` is the state the UI shows (the last one a user settled:
    brush released, slider let go, state loaded); setting it shows that state in every open UI
    tab of the server. ``on_change(callback)`` calls back (on a background thread) with the new
    state each time the user changes it."""

    def __init__(self, url: str, width: Union[int, str] = "100%", height: int = 720, server: Any = None):
        self.url, self.width, self.height = url, width, height
        self._server = server
        parts = urllib.parse.urlsplit(url)
        self._base = f"{parts.scheme}://{parts.netloc}"
        self._token = urllib.parse.parse_qs(parts.query).get("token", [None])[0]
        self._watchers: list = []
        self._stop = threading.Event()

    def _request(self, method: str, path: str, body: Optional[dict] = None) -> dict:
        headers = {"Content-Type": "application/json"}
        if self._token:
            headers["Authorization"] = f"Bearer {self._token}"
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self._base + path, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(request, timeout=30) as response:
                return json.loads(response.read())
        except urllib.error.HTTPError as e:
            try:
                message = json.loads(e.read()).get("error", str(e))
            except ValueError:
                message = str(e)
            raise Error(f"{path}: {message}") from None
        except urllib.error.URLError as e:
            raise Error(f"{self._base}: the RayPC server does not answer ({e.reason})") from None

    def link(self) -> dict:
        """The server's linked state: {"version", "state", "source" ("ui"/"api"), "sessions"}."""
        return self._request("GET", "/api/link")

    @property
    def state(self) -> Optional[State]:
        """The state the UI shows now; None before a UI has shown one."""
        doc = self.link().get("state")
        return None if doc is None else State(doc)

    @state.setter
    def state(self, value: Union[State, dict, str, os.PathLike]) -> None:
        s = value if isinstance(value, State) else State(value)
        self._request("POST", "/api/link", {"state": s.to_dict()})

    def on_change(self, callback: Callable[[State], None], interval: float = 0.25) -> None:
        """Calls ``callback(state)`` each time a user settles a new state in the UI (polls the
        server every ``interval`` seconds on a daemon thread; :meth:`close` stops it)."""
        seen = self.link().get("version", 0)

        def watch() -> None:
            nonlocal seen
            while not self._stop.wait(interval):
                try:
                    link = self.link()
                except Error:
                    continue
                if link.get("version", 0) > seen:
                    seen = link["version"]
                    if link.get("source") == "ui" and link.get("state") is not None:
                        callback(State(link["state"]))

        thread = threading.Thread(target=watch, name="raypc-view-watch", daemon=True)
        thread.start()
        self._watchers.append(thread)

    def wait_for_ui(self, timeout: float = 30) -> None:
        """Returns once a UI tab is connected (raises raypc.Error after `timeout` seconds)."""
        end = time.monotonic() + timeout
        while self.link().get("sessions", 0) == 0:
            if time.monotonic() > end:
                raise Error(f"no browser tab opened {self.url} within {timeout:g} s")
            time.sleep(0.1)

    def close(self) -> None:
        """Stops the callbacks and, when this view started it, the server."""
        self._stop.set()
        for thread in self._watchers:
            thread.join(timeout=2)
        if self._server is not None:
            for key, server in list(_servers.items()):
                if server is self._server:
                    del _servers[key]
            self._server.stop()
            self._server = None

    def _repr_html_(self) -> str:
        width = self.width if isinstance(self.width, str) else f"{int(self.width)}px"
        return (f'<iframe src="{self.url}" style="width:{width};height:{int(self.height)}px;border:0" '
                f'allow="fullscreen; xr-spatial-tracking"></iframe>')

    def __repr__(self) -> str:
        return f"<raypc.View {self.url}>"


def show(dataset: Union[Dataset, str, os.PathLike], host: str = "127.0.0.1", port: int = 0,
         width: Union[int, str] = "100%", height: int = 720) -> View:
    """Serves the dataset's browser UI from this process (``raypc serve``'s server on its own
    thread, on loopback unless ``host`` says otherwise, where the token rules apply; ``port`` 0:
    any free port) — or reuses the server started earlier for it — and returns a :class:`View`,
    which a notebook displays inline."""
    ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
    key = (str(ds.path), host, port)
    server = _servers.get(key)
    if server is None:
        server = _raypc.Server(str(ds.path), host, port, assets=_inside_package("web", needs="index.html"),
                               examples=_inside_package("examples"))
        _servers[key] = server
    return View(server.url, width, height, server)
