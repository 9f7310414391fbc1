"""The teach page's gate, as Jupyter keeps its notebooks: a token in the URL printed at start, then a
cookie, and no websocket from a page of another origin.

- A request without the token (in the URL's `?token=` or the cookie it sets) gets 403 and nothing of the page.
- The token in the URL sets an HttpOnly, SameSite=Strict cookie, so the page's own websocket carries it
  (viser's client drops the URL's query when it connects).
- A websocket whose Origin is not the page's own (`http://` + the request's Host) gets 403 before
  viser reads a message: another site open in the operator's browser cannot press a button.
- What a client may change is what an operator can: a widget's value, on a widget that is not
  disabled, text at most `MAX_TEXT` characters (`filter_client_updates`). viser applies any property a
  client sends (a tab could disable "Save demo" for every tab); the rest is dropped.

viser 1.1.1 serves its page and websocket through one `websockets.asyncio.server.serve(...,
process_request=...)` call and has no hook for either check; `gated_server` wraps that call's
`process_request` while the server starts (hand-written: no library puts a token in front of viser).
"""
from __future__ import annotations

import hmac
import http
import secrets
import threading
from contextlib import contextmanager
from http.cookies import CookieError, SimpleCookie
from typing import Any, Callable, Iterator
from urllib.parse import parse_qs, urlsplit

COOKIE = "nift_teach_token"
MAX_TEXT = 200  # characters a text field takes from a client
_patching = threading.Lock()  # one gated start at a time: the wrapped call is a module attribute


def new_token() -> str:
    return secrets.token_urlsafe(24)


def _given(request: Any) -> tuple[str | None, bool]:
    """(the token the request carries, whether it came in the URL)."""
    query = parse_qs(urlsplit(request.path).query).get("token")
    if query:
        return query[0], True
    try:
        cookies = SimpleCookie(request.headers.get("Cookie", ""))
    except CookieError:
        return None, False
    return (cookies[COOKIE].value if COOKIE in cookies else None), False


def refusal(request: Any, token: str) -> str | None:
    """Why the request is refused (one line), or None to let it through."""
    given, _ = _given(request)
    if given is None or not hmac.compare_digest(given.encode(), token.encode()):
        return "no token or a wrong one: open the URL `nift teach --web` printed"
    if request.headers.get("Upgrade", "").lower() == "websocket":
        origin, host = request.headers.get("Origin"), request.headers.get("Host")
        if origin is None or urlsplit(origin).netloc != host or urlsplit(origin).scheme not in ("http", "https"):
            return f"websocket from {origin!r} refused: only the page's own origin (http://{host}) may connect"
    return None


def _gate(inner: Callable | None, token: str) -> Callable:
    """viser's `process_request` behind the token and Origin checks."""

    def process_request(connection: Any, request: Any) -> Any:
        why = refusal(request, token)
        if why is not None:
            return connection.respond(http.HTTPStatus.FORBIDDEN, why + "\n")
        response = inner(connection, request) if inner is not None else None
        if response is not None and _given(request)[1]:
            response.headers["Set-Cookie"] = f"{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/"
        return response

    return process_request


@contextmanager
def _gated_serve(token: str) -> Iterator[None]:
    import websockets.asyncio.server as ws_server

    serve = ws_server.serve

    def gated(*args: Any, process_request: Callable | None = None, **kwargs: Any) -> Any:
        return serve(*args, process_request=_gate(process_request, token), **kwargs)

    with _patching:
        ws_server.serve = gated
        try:
            yield
        finally:
            ws_server.serve = serve


def gated_server(token: str, **viser_kwargs: Any):
    """A `viser.ViserServer` that answers only requests carrying `token` and websockets of its own origin,
    and takes from its clients only what an operator can change (`filter_client_updates`)."""
    import viser

    filter_client_updates()
    with _gated_serve(token):
        return viser.ViserServer(**viser_kwargs)  # returns once its server is listening (gated)


def operator_updates(updates: dict, disabled: bool) -> dict:
    """Of a client's widget updates, what an operator could have made: the value alone, none on a disabled
    widget, text cut to MAX_TEXT characters."""
    if disabled or "value" not in updates:
        return {}
    value = updates["value"]
    return {"value": value[:MAX_TEXT] if isinstance(value, str) else value}


def filter_client_updates() -> None:
    """Put `operator_updates` in front of viser's handling of a client's widget updates (once per process:
    viser registers its handler when a server is made and has no hook for this)."""
    from viser import _gui_api, _messages

    api = _gui_api.GuiApi
    if getattr(api, "_nift_filtered", False):
        return
    handle_updates = api._handle_gui_updates

    async def filtered(self, client_id, message: _messages.GuiUpdateMessage) -> None:
        handle = self._gui_input_handle_from_uuid.get(message.uuid, None)
        if handle is None:
            return
        updates = operator_updates(message.updates, bool(getattr(handle._impl.props, "disabled", False)))
        if updates:
            await handle_updates(self, client_id, _messages.GuiUpdateMessage(message.uuid, updates))

    api._handle_gui_updates = filtered
    api._nift_filtered = True
