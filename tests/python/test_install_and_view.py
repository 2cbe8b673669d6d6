"""The notebook view's server with its linked state (/api/link; the browser side is tests/browser's
link case). The installed package (pip) is test_wheel.py's."""
import json
import urllib.request

import pytest

import raypc


def get(url):
    with urllib.request.urlopen(url, timeout=10) as r:
        return r.status, r.headers.get("Content-Type", ""), r.read()


def test_show_serves_the_ui_and_links_the_state(contest):
    view = raypc.show(contest)
    try:
        assert view.url.startswith("http://127.0.0.1:") and "token" not in view.url
        again = raypc.show(contest)
        assert again._server is view._server  # reused
        again.close()  # the other view keeps it
        status, kind, body = get(view.url)
        assert status == 200 and "text/html" in kind and b"<script" in body
        info = json.loads(get(view.url.rstrip("/") + "/api/info")[2])
        assert info["steps"] and len(info["steps"]) == 3
        assert '<iframe src="' + view.url in view._repr_html_()

        link = view.link()
        assert link["version"] == 0 and view.state is None and link["sessions"] == 0
        state = raypc.State({"step": 2, "brushes": [{"name": "depth", "min": 560, "max": 760}]})
        view.state = state
        link = view.link()
        assert link["version"] == 1 and link["source"] == "api"
        assert view.state.brushes == [{"name": "depth", "min": 560, "max": 760}] and view.state.step == 2
        with pytest.raises(raypc.Error, match="pressure"):
            view.state = {"brushes": [{"name": "pressure", "min": 0, "max": 1}]}
        with pytest.raises(raypc.Error, match="step: 40 out of range"):
            view.state = {"step": 40}
        assert view.link()["version"] == 1  # refused states change nothing
    finally:
        view.close()
    with pytest.raises(raypc.Error, match="this view is closed"):
        view.link()


def test_show_off_loopback_needs_the_token(contest):
    view = raypc.show(contest, host="0.0.0.0")
    try:
        assert "token=" in view.url
        port = view.url.split(":")[2].split("/")[0]
        with pytest.raises(urllib.error.HTTPError) as refused:
            get(f"http://127.0.0.1:{port}/api/link")
        assert refused.value.code in (401, 403)
        assert view.link()["version"] == 0  # the view sends the token
    finally:
        view.close()


def test_on_change_follows_the_settled_states_of_a_ui_tab(contest):
    """A WebSocket client stands in for a UI tab (the browser side is tests/browser's link case)."""
    import threading

    import websocket

    view = raypc.show(contest)
    seen, called = [], threading.Event()
    view.on_change(lambda s: (seen.append(s), called.set()), interval=0.05)
    tab = websocket.create_connection(view.url.replace("http://", "ws://").rstrip("/") + "/ws", timeout=10)
    try:
        tab.send(json.dumps({"type": "hello", "protocol": 1}))
        assert json.loads(tab.recv())["type"] == "hello"
        view.wait_for_ui(timeout=10)
        brushed = raypc.State({"step": 1, "image": {"width": 64, "height": 48},
                               "brushes": [{"name": "lat", "min": -20, "max": 20}]}).to_dict()
        dragging = dict(brushed, brushes=[{"name": "lat", "min": -10, "max": 20}])
        tab.send(json.dumps({"type": "state", "id": 1, "state": dragging, "interactive": True}))
        assert not called.wait(0.6)  # a state being dragged is not a change
        tab.send(json.dumps({"type": "state", "id": 2, "state": brushed, "interactive": False}))
        assert called.wait(10)
        assert seen[-1].brushes == [{"name": "lat", "min": -20, "max": 20}] and seen[-1].step == 1
        assert view.link()["source"] == "ui" and view.state == seen[-1]

        # and the other way: a state set here reaches the tab as a `link` message
        view.state = {"step": 2, "brushes": [{"name": "depth", "min": 560, "max": 760}]}
        while True:
            opcode, data = tab.recv_data()
            if opcode == websocket.ABNF.OPCODE_TEXT and json.loads(data)["type"] == "link":
                pushed = json.loads(data)
                break
        assert pushed["state"]["step"] == 2 and pushed["state"]["brushes"][0]["name"] == "depth"
        assert len(seen) == 1  # a state set from Python is not the UI's change
    finally:
        tab.close()
        view.close()
