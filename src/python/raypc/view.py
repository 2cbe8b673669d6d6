"""The browser UI of a dataset in a notebook, linked both ways: the server this process starts for
it, and the view that reads and sets the state the UI shows through the server's /api/link."""
from __future__ import annotations

import atexit
import http.client
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


class _Shared:
    """A server show() started, reused by later show() calls of the same dataset, and the number of
    open views that use it: the last one to close stops it."""

    def __init__(self, server: Any):
        self.server, self.views = server, 0


_servers: dict = {}  # (dataset dir, host, port) -> _Shared
_servers_lock = threading.Lock()  # views are closed from any thread (a callback, atexit)


def _inside_package(name: str, needs: str = "") -> Optional[str]:
    """The package's copy of the UI (``web``) or of the example states (``examples``), which an
    installed package carries (setup.py puts them there); None in the build tree, where the server
    finds them in the source tree as the executable does."""
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), name)
    return path if os.path.isdir(path) and (not needs or os.path.isfile(os.path.join(path, needs))) else None


@atexit.register
def _stop_servers() -> None:
    """Stops the servers show() started before the interpreter goes away under their threads."""
    with _servers_lock:
        shared = list(_servers.values())
        _servers.clear()
    for s in shared:
        s.server.stop()


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
        self._closed = False
        self.timeout = 30.0  # seconds a request to the server may take before raypc.Error

    def _request(self, method: str, path: str, body: Optional[dict] = None) -> dict:
        if self._closed:
            raise Error(f"{self.url}: this view is closed")
        headers = {"Content-Type": "application/json"}
        if self._token:
            headers["Authorization"] = f"Bearer {self._token}"
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self._base + path, data=data, method=method, headers=headers)
        try:
            with urllib.request.urlopen(request, timeout=self.timeout) as response:
                return json.loads(response.read())
        except urllib.error.HTTPError as e:
            try:
                message = json.loads(e.read()).get("error", str(e))
            except ValueError:
                message = str(e)
            raise Error(f"{path}: {message}") from None
        except urllib.error.URLError as e:
            raise Error(f"{self._base}{path}: the RayPC server does not answer ({e.reason})") from None
        except OSError as e:  # a timeout or a connection reset while reading the answer
            reason = f"no answer within {self.timeout:g} s" if isinstance(e, TimeoutError) else (e.strerror or str(e))
            raise Error(f"{self._base}{path}: the RayPC server does not answer ({reason})") from None
        except (http.client.HTTPException, ValueError):  # not HTTP, or not JSON: something else listens there
            raise Error(f"{self._base}{path}: the answer is not a RayPC server's") from None

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
        """Stops this view's callbacks and, when it is the last open view of a server this process
        started (show() gives every view of a dataset the same server), the server, which frees its
        port. Closing again does nothing."""
        self._closed = True
        self._stop.set()
        for thread in self._watchers:
            if thread is not threading.current_thread():  # close() called from an on_change callback
                thread.join(timeout=2)
        server, self._server = self._server, None
        if server is None:
            return
        with _servers_lock:
            for key, shared in list(_servers.items()):
                if shared.server is server:
                    shared.views -= 1
                    if shared.views > 0:
                        return  # another view still shows it
                    del _servers[key]
        server.stop()

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
    which a notebook displays inline. The server stops when the last of its views is closed."""
    ds = dataset if isinstance(dataset, Dataset) else Dataset(dataset)
    key = (str(ds.path), host, port)
    with _servers_lock:
        shared = _servers.get(key)
        if shared is None:
            server = _raypc.Server(str(ds.path), host, port, assets=_inside_package("web", needs="index.html"),
                                   examples=_inside_package("examples"))
            shared = _servers[key] = _Shared(server)
        shared.views += 1
    return View(shared.server.url, width, height, shared.server)
