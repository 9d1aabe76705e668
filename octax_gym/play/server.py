"""The play server: aiohttp serving the page, its static files and one WebSocket, where the game runs.

    server = PlayServer(Session("Brix"))
    server.run(port=0)                        # blocks; prints http://127.0.0.1:PORT/
    handle = start_in_thread(Session("Brix")) # for tests and notebooks: handle.url, handle.stop()

The env steps here, on the server's one clock (a task started with the server, whatever the pages
do): at speed 1, one step every frames_per_step / 60 s (15 steps, 60 frames a second at 4 frames a
step); the page only draws the frames it is sent and sends keys. One page plays at a time: a second
one takes over (the seat changes hands in one statement, so pages arriving together cannot each
think they hold it) and the first is told so and closed.

Security: the server binds 127.0.0.1 unless told otherwise; on any loopback address it answers only
requests whose Host is its own address (no DNS rebinding: `octax_gym.play.hosts`), accepts a
WebSocket only from a page of its own origin, serves only `/`, the files in `static/` and `/ws`,
and refuses and logs any message that breaks the protocol (`octax_gym.play.protocol`) without
stopping. A connection that is not the game's WebSocket is closed after a few seconds and past a
cap new ones are refused (`octax_gym.play.connections`).
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import json
import logging
import signal
import threading
import time
from pathlib import Path
from typing import Optional

from aiohttp import WSMsgType, web

from octax_gym.envs.vector import FRAMES_PER_SECOND
from octax_gym.play import hosts, protocol
from octax_gym.play.connections import MAX_CONNECTIONS, REQUEST_TIMEOUT, ConnectionGuard, GuardedRunner
from octax_gym.play.session import Session

log = logging.getLogger("octax_gym.play")
STATIC = Path(__file__).parent / "static"
STATIC_FILES = {"play.js": "text/javascript", "play.css": "text/css"}
WS_MAX_BYTES = 64 * 1024   # aiohttp closes the connection past this (code 1009); protocol's own limit is lower


class PlayServer:
    """The web app around one `Session`.

    Args:
        session: the game.
        host: the address to bind (default 127.0.0.1, this machine only). Any loopback address
            keeps the Host check on; only a bind beyond loopback accepts any Host header (whoever
            can reach it can play: the command line warns).
        request_timeout: seconds a connection that is not the game's WebSocket stays open.
        max_connections: connections open at once; past it new ones are refused (503).
    """

    def __init__(self, session: Session, *, host: str = "127.0.0.1", request_timeout: float = REQUEST_TIMEOUT,
                 max_connections: int = MAX_CONNECTIONS):
        self.session = session
        self.host = host
        self.allow_any_host = not hosts.is_loopback(host)
        self.guard = ConnectionGuard(request_timeout=request_timeout, max_connections=max_connections,
                                     report=self._refuse)
        self.port: Optional[int] = None
        self.paused = False
        self.speed = 1.0
        self.refused: collections.deque[str] = collections.deque(maxlen=1000)  # why, for tests and tools
        self.connections = 0
        self._ws: Optional[web.WebSocketResponse] = None  # the page holding the seat
        self._wake: Optional[asyncio.Event] = None        # set: the clock looks again at once
        self._clock_task: Optional[asyncio.Task] = None
        self.app = web.Application(middlewares=[self._guard], client_max_size=1024)
        self.app.router.add_get("/", self._index)
        self.app.router.add_get("/static/{name}", self._static)
        self.app.router.add_get("/ws", self._websocket)
        self.app.on_shutdown.append(self._on_shutdown)

    # --- HTTP ------------------------------------------------------------------------------

    def allowed_host(self, host: Optional[str]) -> bool:
        return self.allow_any_host or hosts.answers(host, bind=self.host, port=self.port)

    @web.middleware
    async def _guard(self, request: web.Request, handler):
        if not self.allowed_host(request.host):
            self._refuse(f"request with Host {request.host!r} (not this server's address)")
            return web.Response(status=403, text="forbidden host\n")
        if request.method != "GET":
            return web.Response(status=405, text="only GET\n")
        response = await handler(request)
        response.headers["Content-Security-Policy"] = (
            f"default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
            f"connect-src ws://{request.host}; base-uri 'none'; form-action 'none'; frame-ancestors 'none'")
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["Referrer-Policy"] = "no-referrer"
        response.headers["Cache-Control"] = "no-store"
        return response

    async def _index(self, request: web.Request) -> web.Response:
        return web.Response(body=(STATIC / "index.html").read_bytes(), content_type="text/html", charset="utf-8")

    async def _static(self, request: web.Request) -> web.Response:
        name = request.match_info["name"]
        if name not in STATIC_FILES:  # a fixed list: no path from the request ever reaches the disk
            raise web.HTTPNotFound()
        return web.Response(body=(STATIC / name).read_bytes(), content_type=STATIC_FILES[name], charset="utf-8")

    # --- the WebSocket -----------------------------------------------------------------------

    async def _websocket(self, request: web.Request) -> web.StreamResponse:
        origin = request.headers.get("Origin")
        if origin != f"http://{request.host}":
            self._refuse(f"WebSocket from origin {origin!r} (only http://{request.host})")
            return web.Response(status=403, text="forbidden origin\n")
        ws = web.WebSocketResponse(max_msg_size=WS_MAX_BYTES, heartbeat=30)
        await ws.prepare(request)
        self.guard.keep(request.transport)
        session = self.session
        await self._send(ws, session.hello())
        await self._send(ws, self.state())
        await self._send(ws, session.message())
        old, self._ws = self._ws, ws  # the seat, taken in one statement: nothing awaited in between
        self.connections += 1
        self._wake.set()
        limit = protocol.RateLimit()
        last_error = 0.0
        try:
            if old is not None and not old.closed:
                await self._send(old, {"type": "error", "message": "another page took over the game"})
                await old.close(code=4000, message=b"another page took over")
            async for msg in ws:
                if msg.type == WSMsgType.ERROR:
                    exc = ws.exception()
                    big = getattr(exc, "code", None) == 1009 or ws.close_code == 1009
                    self._refuse(f"message too big: connection closed ({exc})" if big else f"WebSocket error: {exc!r}")
                    break
                if not limit.allow():
                    if limit.flooding:
                        self._refuse("flood: closing the connection")
                        await ws.close(code=1008, message=b"too many messages")
                        break
                    if limit.refused % 100 == 1:
                        self._refuse(f"flood: {limit.refused} message(s) over {limit.rate:.0f}/s refused")
                    continue
                try:
                    if msg.type != WSMsgType.TEXT:
                        raise protocol.ProtocolError("only text messages (JSON) are accepted")
                    message = protocol.parse(msg.data)
                    await self._apply(ws, message)
                except (protocol.ProtocolError, ValueError) as exc:
                    self._refuse(str(exc))
                    now = time.monotonic()
                    if now - last_error >= 1.0:
                        last_error = now
                        await self._send(ws, {"type": "error", "message": str(exc)})
        finally:
            if self._ws is ws:
                self._ws = None
                session.held.clear()
        return ws

    async def _apply(self, ws: web.WebSocketResponse, message: protocol.Message) -> None:
        session = self.session
        if message.type == "key":
            session.key(message.key, message.down, message.seq)
            return
        if message.type == "pause":
            self.paused = message.paused
        elif message.type == "speed":
            self.speed = message.speed
        elif message.type == "seat":
            session.set_player(message.seat, message.player)
        elif message.type == "reset":
            await self._send(ws, session.reset())
            self._wake.set()
            return
        elif message.type == "step":
            if self.paused:
                await self._send(ws, session.step())
            return
        await self._send(ws, self.state())
        self._wake.set()

    async def _clock(self) -> None:
        """Steps the game on time for the page holding the seat: one step every frames_per_step /
        60 / speed seconds. One task per server, started with it: however many pages connect, at
        whatever moments, the game has this one clock."""
        loop = asyncio.get_running_loop()
        next_tick = loop.time()
        while True:
            ws = self._ws
            period = self.session.frames_per_step / FRAMES_PER_SECOND / self.speed
            if ws is None or ws.closed or self.paused or self.session.done:
                self._wake.clear()
                try:
                    await asyncio.wait_for(self._wake.wait(), timeout=0.25)
                except asyncio.TimeoutError:
                    pass
                next_tick = loop.time()
                self.session.step_times.clear()  # the frame rate is of play, not of pauses
                continue
            try:
                message = self.session.step()
            except Exception:  # an agent's or the env's failure: reported, and the game paused
                log.exception("step failed; pausing")
                self.paused = True
                await self._send(ws, {"type": "error", "message": "the step failed (see the server's log); paused"})
                await self._send(ws, self.state())
                continue
            await self._send(ws, message)
            next_tick += period
            delay = next_tick - loop.time()
            if delay < -period:  # fell behind (a long pause of the machine): no burst to catch up
                next_tick, delay = loop.time(), 0.0
            await asyncio.sleep(max(0.0, delay))

    def state(self) -> dict:
        return {"type": "state", "paused": self.paused, "speed": self.speed, "players": list(self.session.players),
                "fps": round(self.session.frames_per_second(), 2)}

    async def _send(self, ws: web.WebSocketResponse, message: dict) -> None:
        if not ws.closed:
            try:
                await ws.send_str(json.dumps(message, separators=(",", ":")))
            except (ConnectionError, RuntimeError):
                pass

    def _refuse(self, why: str) -> None:
        self.refused.append(why)
        log.warning("refused: %s", why)

    async def _on_shutdown(self, app: web.Application) -> None:
        if self._clock_task is not None:
            self._clock_task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._clock_task
            self._clock_task = None
        if self._ws is not None:
            await self._ws.close(code=1001, message=b"server shutting down")

    # --- running -----------------------------------------------------------------------------

    async def start(self, port: int = 0) -> web.AppRunner:
        if not (isinstance(port, int) and 0 <= port <= 65535):
            raise ValueError(f"port must be in 0..65535 (0: a free port), got {port!r}")
        runner = GuardedRunner(self.app, self.guard, access_log=None, handle_signals=False)
        await runner.setup()
        site = web.TCPSite(runner, self.host, port)
        await site.start()
        self.port = site._server.sockets[0].getsockname()[1]
        self._wake = asyncio.Event()
        self._clock_task = asyncio.create_task(self._clock())
        return runner

    @property
    def url(self) -> str:
        host = self.host if self.host not in ("0.0.0.0", "::", "") else "127.0.0.1"
        return f"http://{'[' + host + ']' if ':' in host else host}:{self.port}/"

    def run(self, port: int = 0, on_start=None) -> None:
        """Serves until Ctrl-C; `on_start(url)` is called once the port is open."""
        async def main():
            runner = await self.start(port)
            if on_start is not None:
                on_start(self.url)
            try:
                await asyncio.Event().wait()
            finally:
                await runner.cleanup()

        if threading.current_thread() is threading.main_thread():
            # Ctrl-C stops the server even where this process was started with SIGINT ignored (a
            # shell's background job, a nohup'd script), which Python would otherwise keep.
            signal.signal(signal.SIGINT, signal.default_int_handler)
        try:
            asyncio.run(main())
        except KeyboardInterrupt:
            pass


class ServerThread:
    """A `PlayServer` running in a thread of its own (`start_in_thread`)."""

    def __init__(self, server: PlayServer, port: int = 0):
        self.server = server
        self.loop = asyncio.new_event_loop()
        ready = threading.Event()
        self._runner = None
        failed: list[BaseException] = []

        def main():
            asyncio.set_event_loop(self.loop)
            try:
                self._runner = self.loop.run_until_complete(server.start(port))
            except BaseException as exc:  # a bad port, an address in use: raised in the caller's thread
                failed.append(exc)
                self.loop.close()
                return
            finally:
                ready.set()
            self.loop.run_forever()

        self.thread = threading.Thread(target=main, name="octax-play-server", daemon=True)
        self.thread.start()
        if not ready.wait(60):
            raise RuntimeError("the play server did not start")
        if failed:
            raise failed[0]

    @property
    def url(self) -> str:
        return self.server.url

    def call(self, function, *args):
        """Runs `function(*args)` in the server's thread (between its steps) and returns its result."""
        async def run():
            return function(*args)
        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(30)

    def stop(self) -> None:
        if self.loop.is_running():
            asyncio.run_coroutine_threadsafe(self._runner.cleanup(), self.loop).result(30)
            self.loop.call_soon_threadsafe(self.loop.stop)
            self.thread.join(30)


def start_in_thread(session: Session, *, host: str = "127.0.0.1", port: int = 0) -> ServerThread:
    return ServerThread(PlayServer(session, host=host), port)
