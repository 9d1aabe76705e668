"""Limits on the play server's connections: a deadline for plain HTTP and a cap on how many are open.

    guard = ConnectionGuard(request_timeout=5.0, max_connections=32, report=log.warning)
    runner = GuardedRunner(app, guard)        # an aiohttp AppRunner whose sites accept through the guard
    guard.keep(request.transport)             # a WebSocket: exempt from the deadline

Why: aiohttp waits for a request's head as long as its keep-alive timeout (an hour in aiohttp 3.14),
so 20,000 half-open requests held 20,000 file descriptors until the server could accept nothing.
Here every connection that has not become the game's WebSocket is closed `request_timeout` seconds
after it opened, whatever it sent meanwhile (the page's files are served in milliseconds; a browser
reopens a closed keep-alive connection by itself), and past `max_connections` open connections a
new one is answered 503 and closed at once. What was refused is reported at most once a second, as
counts, so a flood cannot flood the log too.
"""

from __future__ import annotations

import asyncio
import time
from typing import Callable, Optional

from aiohttp import web

REQUEST_TIMEOUT = 5.0   # seconds a connection may take to become a WebSocket (or be done with)
MAX_CONNECTIONS = 32    # open at once: a page needs a few for its files and one for the game
REPORT_EVERY = 1.0      # seconds between two reports of refused connections
REFUSAL = b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"


class ConnectionGuard:
    """Counts the open connections and closes or refuses those past the limits.

    Args:
        request_timeout: seconds a connection that is no WebSocket stays open.
        max_connections: connections open at once; the next is refused.
        report: called with a one-line summary of what was refused, at most once a second.
    """

    def __init__(self, *, request_timeout: float = REQUEST_TIMEOUT, max_connections: int = MAX_CONNECTIONS,
                 report: Callable[[str], None] = print):
        number = isinstance(request_timeout, (int, float)) and not isinstance(request_timeout, bool)
        if not (number and request_timeout > 0):
            raise ValueError(f"request_timeout must be a positive number of seconds, got {request_timeout!r}")
        if isinstance(max_connections, bool) or not isinstance(max_connections, int) or max_connections < 2:
            raise ValueError(f"max_connections must be an int >= 2 (a page's files and its WebSocket), "
                             f"got {max_connections!r}")
        self.timeout = float(request_timeout)
        self.max_open = max_connections
        self.report = report
        self.open = 0
        self.timed_out = 0                 # totals, for tests and tools
        self.refused = 0
        self.kept: set[asyncio.BaseTransport] = set()
        self._unreported = {"timed_out": 0, "refused": 0}
        self._last_report = -float("inf")

    def protocol_factory(self, make_handler: Callable[[], asyncio.Protocol]) -> Callable[[], asyncio.Protocol]:
        """What `loop.create_server` calls per connection: aiohttp's handler behind the guard."""
        return lambda: _Guarded(self, make_handler)

    def keep(self, transport: Optional[asyncio.BaseTransport]) -> None:
        """Exempts a connection (the game's WebSocket) from the deadline."""
        if transport is not None:
            self.kept.add(transport)

    def note(self, what: str) -> None:
        setattr(self, what, getattr(self, what) + 1)
        self._unreported[what] += 1
        now = time.monotonic()
        if now - self._last_report < REPORT_EVERY:
            return
        self._last_report = now
        timed_out, refused = self._unreported["timed_out"], self._unreported["refused"]
        self._unreported = {"timed_out": 0, "refused": 0}
        parts = [f"{timed_out} closed, not a WebSocket {self.timeout:g} s after opening" if timed_out else "",
                 f"{refused} refused past {self.max_open} open" if refused else ""]
        self.report(f"connections: {', '.join(p for p in parts if p)} (since the last report; one a second at most)")


class _Guarded(asyncio.Protocol):
    """One connection: admitted (aiohttp's handler made and fed) or refused, and timed."""

    def __init__(self, guard: ConnectionGuard, make_handler: Callable[[], asyncio.Protocol]):
        self._guard = guard
        self._make_handler = make_handler
        self._handler: Optional[asyncio.Protocol] = None
        self._timer: Optional[asyncio.TimerHandle] = None
        self._transport: Optional[asyncio.Transport] = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        guard = self._guard
        if guard.open >= guard.max_open:
            guard.note("refused")
            transport.write(REFUSAL)
            transport.close()
            return
        guard.open += 1
        self._transport = transport
        self._timer = asyncio.get_running_loop().call_later(guard.timeout, self._expire)
        self._handler = self._make_handler()
        self._handler.connection_made(transport)

    def _expire(self) -> None:
        transport = self._transport
        if transport is None or transport in self._guard.kept or transport.is_closing():
            return
        self._guard.note("timed_out")
        transport.abort()

    def data_received(self, data: bytes) -> None:
        if self._handler is not None:
            self._handler.data_received(data)

    def eof_received(self) -> Optional[bool]:
        return None if self._handler is None else self._handler.eof_received()

    def pause_writing(self) -> None:
        if self._handler is not None:
            self._handler.pause_writing()

    def resume_writing(self) -> None:
        if self._handler is not None:
            self._handler.resume_writing()

    def connection_lost(self, exc: Optional[Exception]) -> None:
        if self._handler is None:
            return
        self._timer.cancel()
        self._guard.open -= 1
        self._guard.kept.discard(self._transport)
        self._handler.connection_lost(exc)


class GuardedRunner(web.AppRunner):
    """An `AppRunner` whose sites accept connections through `guard` (sites take `runner.server`
    as their protocol factory; everything else of the runner is aiohttp's)."""

    def __init__(self, app: web.Application, guard: ConnectionGuard, **kwargs):
        super().__init__(app, **kwargs)
        self.guard = guard

    @property
    def server(self):
        handler_factory = super().server
        return None if handler_factory is None else self.guard.protocol_factory(handler_factory)
