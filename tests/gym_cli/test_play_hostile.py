"""`octax-gym play` against a hostile or careless user (issue 38, items 2, 3 and 8's --seed and
--port): the Host check on every loopback bind, one game clock whatever the connections do,
half-open requests timed out and a cap on open connections, and the CLI's range checks.

One session (Dodge, our own ROM) for the module, seeded with the last seed there is, so every reset
after the first crosses 2**32; each test starts its own server on 127.0.0.1 and stops it. All
traffic stays on 127.0.0.1 and every wait has a deadline.
"""

from __future__ import annotations

import asyncio
import http.client
import json
import logging
import select
import socket
import time

import pytest

aiohttp = pytest.importorskip("aiohttp", reason="octax-gym play needs the play extra (aiohttp)")

from octax_gym.cli import main  # noqa: E402
from octax_gym.play.connections import REFUSAL, REQUEST_TIMEOUT  # noqa: E402
from octax_gym.play.server import PlayServer, ServerThread  # noqa: E402
from octax_gym.play.session import Session  # noqa: E402

GAME = "Dodge"
LAST_SEED = 2**32 - 1


@pytest.fixture(scope="module")
def session():
    game = Session(GAME, seed=LAST_SEED)
    yield game
    game.close()


@pytest.fixture
def serve(session):
    """serve(**PlayServer options) -> a running ServerThread on 127.0.0.1; all stopped at the end."""
    handles = []

    def start(**options):
        handle = ServerThread(PlayServer(session, **options))
        handles.append(handle)
        return handle

    yield start
    for handle in handles:
        handle.stop()


def status_of(port: int, host_header: str, address: str = "127.0.0.1") -> int:
    connection = http.client.HTTPConnection(address, port, timeout=5)
    try:
        connection.request("GET", "/", headers={"Host": host_header})
        return connection.getresponse().status
    finally:
        connection.close()


async def websocket_status(port: int, host_header: str, address: str = "127.0.0.1") -> int:
    """The status of a WebSocket handshake whose Host and Origin both name `host_header`."""
    async with aiohttp.ClientSession() as client:
        try:
            ws = await client.ws_connect(f"http://{address}:{port}/ws", timeout=aiohttp.ClientWSTimeout(ws_close=2),
                                         headers={"Host": host_header, "Origin": f"http://{host_header}"})
        except aiohttp.WSServerHandshakeError as exc:
            return exc.status
        await ws.close()
        return 101


# --- seeds -------------------------------------------------------------------------------------

def test_every_reset_after_the_last_seed_works(session):
    """Episode e is seeded (S + e) mod 2**32: a session seeded 2**32 - 1 goes on with 0, 1, ..."""
    from octax_gym.play.session import episode_seed

    assert [episode_seed(LAST_SEED, e) for e in range(3)] == [LAST_SEED, 0, 1]
    assert episode_seed(5, 2) == 7
    episode = session.episode
    message = session.reset()
    assert message["episode"] == episode + 1 and message["seed"] == (LAST_SEED + episode + 1) % 2**32
    assert session.step()["step"] == 1


@pytest.mark.parametrize("seed", [2**32, -1, True, 1.5, "3"])
def test_session_refuses_a_seed_the_env_cannot_take(seed):
    with pytest.raises(ValueError, match=r"seed must be an int in 0\.\.4294967295"):
        Session(GAME, seed=seed)   # refused before anything is compiled: this takes no time


def test_a_failed_reset_leaves_the_episode_as_it_was(session, monkeypatch):
    def broken(**kwargs):
        raise RuntimeError("the env could not reset")

    episode, seed = session.episode, session.seed
    monkeypatch.setattr(session.env, "reset", broken)
    with pytest.raises(RuntimeError, match="could not reset"):
        session.reset()
    assert (session.episode, session.seed) == (episode, seed)


# --- the command line: --port, --seed, --host ---------------------------------------------------

@pytest.mark.parametrize("args, words", [
    (["--port", "99999"], "--port must be in 0..65535 (0: a free port), got 99999"),
    (["--port", "-1"], "--port must be in 0..65535 (0: a free port), got -1"),
    (["--seed", "4294967296"], "--seed must be in 0..4294967295"),
    (["--seed", "-1"], "--seed must be in 0..4294967295"),
])
def test_cli_refuses_out_of_range_port_and_seed(capsys, args, words):
    start = time.monotonic()
    assert main(["play", GAME, *args]) == 1
    err = capsys.readouterr().err
    assert err.startswith("octax-gym: error: ") and words in err and err.count("\n") == 1, err
    assert "compiling" not in err and time.monotonic() - start < 10   # refused before any work


class Borrowed:
    """The module's session for a CLI run (which closes its session at the end: this one stays)."""

    def __init__(self, session):
        self._session = session

    def __getattr__(self, name):
        return getattr(self._session, name)

    def close(self):
        pass


def run_cli_server(monkeypatch, session, host: str, check) -> PlayServer:
    """Runs `octax-gym play GAME --host HOST` with the module's session; instead of serving until
    Ctrl-C, the server the CLI built is started in a thread, `check(server)` runs, and it stops."""
    built = []

    def run(server, port=0, on_start=None):
        built.append(server)
        if check is not None:
            handle = ServerThread(server, port)
            try:
                check(server)
            finally:
                handle.stop()

    monkeypatch.setattr("octax_gym.play.session.Session", lambda *args, **kwargs: Borrowed(session))
    monkeypatch.setattr(PlayServer, "run", run)
    assert main(["play", GAME, "--host", host]) == 0
    return built[0]


@pytest.mark.parametrize("host", ["127.0.0.1", "localhost", "127.0.0.2"])
def test_cli_loopback_host_keeps_the_host_check(monkeypatch, capsys, session, host):
    """Issue 38, item 2: `--host 127.0.0.1` turned the DNS-rebinding check off."""
    seen = {}

    def check(server):
        address = "127.0.0.2" if host == "127.0.0.2" else "127.0.0.1"
        evil = f"evil.example:{server.port}"
        seen["own"] = status_of(server.port, f"{host}:{server.port}", address)
        seen["foreign"] = status_of(server.port, evil, address)
        seen["ws"] = asyncio.run(websocket_status(server.port, evil, address))

    server = run_cli_server(monkeypatch, session, host, check)
    assert not server.allow_any_host
    assert (seen["own"], seen["foreign"], seen["ws"]) == (200, 403, 403)
    assert "octax-gym play: warning" not in capsys.readouterr().err


def test_cli_any_address_relaxes_the_host_check_with_a_warning(monkeypatch, capsys, session):
    server = run_cli_server(monkeypatch, session, "0.0.0.0", check=None)   # never bound: no traffic leaves
    assert server.allow_any_host
    assert "octax-gym play: warning: binding 0.0.0.0" in capsys.readouterr().err


@pytest.mark.parametrize("host, loopback", [
    ("127.0.0.1", True), ("127.8.9.10", True), ("localhost", True), ("::1", True), ("[::1]", True),
    ("::ffff:127.0.0.1", True), ("0.0.0.0", False), ("::", False), ("", False), ("192.168.1.20", False),
    ("10.0.0.1", False), ("no-such-host.invalid", False),
])
def test_is_loopback(host, loopback):
    from octax_gym.play.hosts import is_loopback

    assert is_loopback(host) is loopback


def test_server_on_another_loopback_address_answers_only_its_names(serve):
    handle = serve(host="127.0.0.2")
    port = handle.server.port
    connection = http.client.HTTPConnection("127.0.0.2", port, timeout=5)
    statuses = []
    for host in (f"127.0.0.2:{port}", f"127.0.0.1:{port}", f"localhost:{port}", f"evil.example:{port}",
                 "127.0.0.2:1"):
        connection.request("GET", "/", headers={"Host": host})
        response = connection.getresponse()
        response.read()
        statuses.append(response.status)
    connection.close()
    assert statuses == [200, 200, 200, 403, 403]


# --- one game clock ------------------------------------------------------------------------------

def test_connections_arriving_together_share_one_clock(serve, session):
    """Issue 38, item 3: three pages at once made 124 steps in 4 s instead of about 60."""
    handle = serve()
    url = handle.url
    pages = 8

    async def page(client, ready, counts, index):
        ws = await client.ws_connect(url + "ws", headers={"Origin": url.rstrip("/")},
                                     timeout=aiohttp.ClientWSTimeout(ws_close=2))
        ready.append(ws)
        deadline = time.monotonic() + 6
        while time.monotonic() < deadline:   # read until closed (the takeover) or the measure is over
            msg = await ws.receive(timeout=max(0.01, deadline - time.monotonic()))
            if msg.type != aiohttp.WSMsgType.TEXT:
                break
            counts[index] += json.loads(msg.data)["type"] == "frame"
        return ws

    async def main():
        async with aiohttp.ClientSession() as client:
            ready, counts = [], [0] * pages
            tasks = [asyncio.create_task(page(client, ready, counts, i)) for i in range(pages)]
            deadline = time.monotonic() + 10
            while len(ready) < pages and time.monotonic() < deadline:
                await asyncio.sleep(0.01)
            await asyncio.sleep(0.5)               # the takeovers settle
            before = handle.call(lambda: session.step_count)
            start = time.monotonic()
            await asyncio.sleep(3.0)
            steps = handle.call(lambda: session.step_count) - before
            seconds = time.monotonic() - start
            open_pages = sum(not ws.closed for ws in ready)
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
            for ws in ready:
                await ws.close()
            return len(ready), steps / seconds, open_pages

    handle.call(session.reset)   # a fresh episode: the game runs all along
    connected, steps_per_second, open_pages = asyncio.run(main())
    print(f"\n{pages} pages at once: {steps_per_second:.1f} steps/s, {open_pages} page(s) left playing")
    assert connected == pages
    assert 8.0 <= steps_per_second <= 16.5   # one clock: 15 steps/s (a loaded machine may lag, never double)
    assert open_pages == 1


# --- half-open requests and the cap on connections ------------------------------------------------

def half_open(port: int, host: str = "127.0.0.1") -> socket.socket:
    sock = socket.create_connection((host, port), timeout=5)
    sock.sendall(f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n".encode())   # the head never ends
    return sock


def closed_by_server(sock: socket.socket, wait: float) -> tuple[bool, bytes]:
    """(whether the server closed `sock` within `wait` seconds, what it sent before); wait 0: by now."""
    data, deadline = b"", time.monotonic() + wait
    while True:
        if not select.select([sock], [], [], max(0.0, deadline - time.monotonic()))[0]:
            return False, data
        try:
            chunk = sock.recv(4096)
        except ConnectionResetError:
            return True, data
        if not chunk:
            return True, data
        data += chunk


def test_half_open_requests_are_closed_and_the_cap_refuses_the_rest(serve, caplog):
    timeout, cap, extra = 1.5, 6, 60
    handle = serve(request_timeout=timeout, max_connections=cap)
    port = handle.server.port
    with caplog.at_level(logging.WARNING, logger="octax_gym.play"):
        opened = time.monotonic()
        socks = [half_open(port) for _ in range(cap + extra)]
        time.sleep(0.5)
        first = [closed_by_server(sock, 0.0) for sock in socks]
        refused = [data for closed, data in first if closed]
        held = [sock for sock, (closed, _) in zip(socks, first) if not closed]
        assert len(refused) == extra and len(held) == cap
        # (a refused socket whose request was unread when closed may get a reset before the 503)
        assert all(data == b"" or data.startswith(b"HTTP/1.1 503") for data in refused)
        probe = socket.create_connection(("127.0.0.1", port), timeout=5)
        assert closed_by_server(probe, 2.0) == (True, REFUSAL)   # full: the next one is refused too
        probe.close()
        results = [closed_by_server(sock, timeout + 2.0 - (time.monotonic() - opened)) for sock in held]
        took = time.monotonic() - opened
        for sock in socks:
            sock.close()
        assert all(closed for closed, _ in results), f"{sum(not c for c, _ in results)} still open after {took:.1f} s"
        assert timeout - 0.2 <= took <= timeout + 2.0
        assert status_of(port, f"127.0.0.1:{port}") == 200   # and the server serves the next request
        records = [r for r in caplog.records if r.name == "octax_gym.play"]
    assert handle.server.guard.refused == extra + 1 and handle.server.guard.timed_out == cap
    assert 1 <= len(records) <= 4, [r.getMessage() for r in records]   # counts, at most one line a second
    deadline = time.monotonic() + 2.0   # the last request's close reaches the server in a moment
    while handle.call(lambda: handle.server.guard.open) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert handle.call(lambda: handle.server.guard.open) == 0   # every connection counted out again


def test_a_trickled_request_head_is_closed_on_time(serve):
    """A slowloris: a header line every 0.5 s does not extend the deadline (the default, 5 s)."""
    handle = serve()
    sock = half_open(handle.server.port)
    start, closed = time.monotonic(), False
    while not closed and time.monotonic() - start < REQUEST_TIMEOUT + 2.0:
        try:
            sock.sendall(b"X-Slow: 1\r\n")
        except (BrokenPipeError, ConnectionResetError):
            closed = True
            break
        closed = closed_by_server(sock, 0.5)[0]
    took = time.monotonic() - start
    sock.close()
    assert closed and REQUEST_TIMEOUT - 0.5 <= took <= REQUEST_TIMEOUT + 2.0, took


def test_a_websocket_outlives_the_request_timeout(serve):
    handle = serve(request_timeout=1.0)
    url = handle.url

    async def main():
        async with aiohttp.ClientSession() as client:
            async with client.ws_connect(url + "ws", headers={"Origin": url.rstrip("/")}) as ws:
                start = time.monotonic()
                frames = 0
                while time.monotonic() - start < 2.5:
                    msg = await ws.receive(timeout=2)
                    assert msg.type == aiohttp.WSMsgType.TEXT, msg
                    frames += json.loads(msg.data)["type"] == "frame"
                return frames, ws.closed

    frames, closed = asyncio.run(main())
    assert frames >= 20 and not closed


@pytest.mark.parametrize("port", [99999, -1])
def test_server_refuses_a_port_out_of_range(session, port):
    start = time.monotonic()
    with pytest.raises(ValueError, match=r"port must be in 0\.\.65535"):
        ServerThread(PlayServer(session), port)
    assert time.monotonic() - start < 10   # raised in the caller, not after the thread's 60 s wait


@pytest.mark.parametrize("options, words", [
    ({"request_timeout": 0}, "request_timeout must be a positive number"),
    ({"max_connections": 1}, "max_connections must be an int >= 2"),
])
def test_server_limits_are_checked(session, options, words):
    with pytest.raises(ValueError, match=words):
        PlayServer(session, **options)
