"""The teach page's gate (app.teach.gate) on a real viser server: a request without the URL's token is
refused, and so is a websocket from another origin, from Python's websockets and from Chromium."""
from __future__ import annotations

import http.server
import socket
import threading
import urllib.error
import urllib.request

import pytest
import viser
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from app.teach.gate import COOKIE, gated_server

PROTOCOL = f"viser-v{viser.__version__}"
OPEN_SOCKET = """
const done = arguments[arguments.length - 1];
const ws = new WebSocket(arguments[0], [arguments[1]]);
ws.onopen = () => { ws.close(); done("open"); };
ws.onerror = () => done("refused");
setTimeout(() => done("timeout"), 10000);
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def served():
    port = free_port()
    server = gated_server("s3cret-token", host="127.0.0.1", port=port, verbose=False)
    try:
        yield f"127.0.0.1:{port}"
    finally:
        server.stop()


def status(url: str, headers: dict | None = None) -> tuple[int, str | None]:
    try:
        with urllib.request.urlopen(urllib.request.Request(url, headers=headers or {}), timeout=10) as r:
            return r.status, r.headers.get("Set-Cookie")
    except urllib.error.HTTPError as exc:
        return exc.code, None


def opens(address: str, origin: str | None, cookie: str | None) -> bool:
    headers = {"Cookie": f"{COOKIE}={cookie}"} if cookie else {}
    try:
        with connect(f"ws://{address}", origin=origin, additional_headers=headers, subprotocols=[PROTOCOL],
                     open_timeout=10):
            return True
    except InvalidStatus as exc:
        assert exc.response.status_code == 403
        return False


def test_only_the_token_opens_the_page_and_only_the_pages_origin_its_websocket(served):
    page = f"http://{served}"
    assert status(page)[0] == 403 and status(f"{page}/?token=s3cret-tokeN")[0] == 403
    code, cookie = status(f"{page}/?token=s3cret-token")
    assert code == 200 and cookie.startswith(f"{COOKIE}=s3cret-token;") and "HttpOnly" in cookie
    assert status(page, {"Cookie": f"{COOKIE}=s3cret-token"})[0] == 200
    assert opens(served, page, "s3cret-token")
    assert not opens(served, "http://evil.example", "s3cret-token")  # another site, the operator's cookie
    assert not opens(served, page, None) and not opens(served, page, "guess")
    assert not opens(served, None, "s3cret-token")  # no Origin at all


def test_in_chromium_a_page_of_another_origin_cannot_open_the_teach_pages_websocket(served):
    from app.teach.operator import chromium

    class Plain(http.server.SimpleHTTPRequestHandler):
        def do_GET(self) -> None:
            body = b"<html><body>another site</body></html>"
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args) -> None:
            pass

    other = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Plain)  # same host, another port: another origin
    threading.Thread(target=other.serve_forever, daemon=True).start()
    driver = chromium()
    try:
        driver.set_script_timeout(20)
        driver.get(f"http://{served}/")
        assert "no token or a wrong one" in driver.page_source  # a browser without the token sees nothing
        driver.get(f"http://{served}/?token=s3cret-token")  # the operator opens the printed URL
        assert driver.execute_async_script(OPEN_SOCKET, f"ws://{served}", PROTOCOL) == "open"
        driver.get(f"http://127.0.0.1:{other.server_address[1]}/")  # then another page, in the same browser
        assert driver.execute_async_script(OPEN_SOCKET, f"ws://{served}", PROTOCOL) == "refused"
    finally:
        driver.quit()
        other.shutdown()


SEND = """
const done = arguments[arguments.length - 1];
const messages = arguments[2];
const ws = new WebSocket(arguments[0], [arguments[1]]);
ws.onopen = () => { for (const m of messages) ws.send(new Uint8Array(m)); setTimeout(() => { ws.close(); done("sent"); }, 500); };
ws.onerror = () => done("refused");
setTimeout(() => done("timeout"), 10000);
"""


def test_in_chromium_a_tab_changes_only_what_an_operator_can():
    """A tab of the operator's browser (Chromium, the page opened with its token) sends, over the page's
    own websocket, an update that drops the Save button's callbacks, a click, and a 10,000-character
    text: the callbacks stay (the click saves), the text is cut to MAX_TEXT; a click on a disabled
    button does nothing. viser alone applied every one of them."""
    import time

    import msgspec

    from app.teach.gate import MAX_TEXT
    from app.teach.operator import chromium

    port = free_port()
    server = gated_server("s3cret-token", host="127.0.0.1", port=port, verbose=False)
    saved = []
    save = server.gui.add_button("Save demo")
    save.on_click(lambda _: saved.append(1))
    name = server.gui.add_text("Name", "mug")

    def update(handle, **updates) -> list[int]:
        return list(msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": handle._impl.uuid, "updates": updates}))

    camera = list(msgspec.msgpack.encode({  # a browser's first message: viser counts the client connected then
        "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [1.0, 1.0, 1.0], "fov": 1.0,
        "near": 0.01, "far": 100.0, "image_height": 600, "image_width": 800, "look_at": [0.0, 0.0, 0.0],
        "up_direction": [0.0, 0.0, 1.0]}))
    driver = chromium()
    try:
        driver.set_script_timeout(20)
        driver.get(f"http://127.0.0.1:{port}/?token=s3cret-token")
        sent = driver.execute_async_script(SEND, f"ws://127.0.0.1:{port}", PROTOCOL, [
            camera, update(save, update_cb=[], removed=True), update(save, value=True), update(name, value="x" * 10_000)])
        assert sent == "sent"
        deadline = time.monotonic() + 5
        while (not saved or name.value == "mug") and time.monotonic() < deadline:
            time.sleep(0.05)
        assert saved == [1] and name.value == "x" * MAX_TEXT
        save.disabled = True
        assert driver.execute_async_script(SEND, f"ws://127.0.0.1:{port}", PROTOCOL, [camera, update(save, value=True)]) == "sent"
        time.sleep(0.5)
        assert saved == [1]
    finally:
        driver.quit()
        server.stop()
