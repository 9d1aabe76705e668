"""`octax-gym play` without a browser: the WebSocket protocol's checks, hostile input against a live
server (which must refuse it, log it and keep serving), the server's frame rate, the two-player
session, recording, agents and the command line.

One live server (Dodge, our own game: no third-party ROM) for the whole module; each test talks to
it with aiohttp's client.
"""

from __future__ import annotations

import asyncio
import json
import time

import numpy as np
import pytest

aiohttp = pytest.importorskip("aiohttp", reason="octax-gym play needs the play extra (aiohttp)")

from octax_gym.play import protocol  # noqa: E402
from octax_gym.play.server import start_in_thread  # noqa: E402
from octax_gym.play.session import Session  # noqa: E402

GAME = "Dodge"


@pytest.fixture(scope="module")
def live():
    handle = start_in_thread(Session(GAME, seed=3))
    yield handle
    handle.stop()


def origin(handle) -> str:
    return handle.url.rstrip("/")


def run(coroutine):
    return asyncio.run(coroutine)


async def receive_json(ws, kind: str, timeout: float = 5.0) -> dict:
    """The next message of type `kind` (others skipped)."""
    deadline = time.monotonic() + timeout
    while True:
        msg = await ws.receive(timeout=max(0.01, deadline - time.monotonic()))
        if msg.type != aiohttp.WSMsgType.TEXT:
            raise AssertionError(f"expected {kind}, got {msg.type} {msg.data!r} {msg.extra!r}")
        data = json.loads(msg.data)
        if data["type"] == kind:
            return data


async def connect(session, handle, **headers):
    return await session.ws_connect(handle.url + "ws", headers={"Origin": origin(handle), **headers})


async def still_serving(handle) -> dict:
    """A new page connects, gets the game and a frame, and its pause is obeyed."""
    async with aiohttp.ClientSession() as client:
        async with await connect(client, handle) as ws:
            hello = await receive_json(ws, "hello")
            await receive_json(ws, "frame")
            await ws.send_str(json.dumps({"type": "pause", "paused": True}))
            state = await receive_json(ws, "state")
            assert state["paused"] is True
            await ws.send_str(json.dumps({"type": "pause", "paused": False}))
            assert (await receive_json(ws, "state"))["paused"] is False
            return hello


# --- the parser alone --------------------------------------------------------------------------

@pytest.mark.parametrize("text, kind", [
    ('{"type":"key","key":15,"down":true,"seq":7}', "key"),
    ('{"type":"key","key":0,"down":false}', "key"),
    ('{"type":"pause","paused":true}', "pause"),
    ('{"type":"step"}', "step"),
    ('{"type":"reset"}', "reset"),
    ('{"type":"speed","speed":0.25}', "speed"),
    ('{"type":"speed","speed":1}', "speed"),
    ('{"type":"seat","seat":1,"player":"scripted"}', "seat"),
])
def test_parse_accepts_the_protocol(text, kind):
    assert protocol.parse(text).type == kind


@pytest.mark.parametrize("data, why", [
    ("not json", "not JSON"),
    ("{", "not JSON"),
    ("[1, 2]", "JSON object"),
    ('"key"', "JSON object"),
    ("NaN", "not JSON"),
    ('{"type":"jump"}', "unknown message type"),
    ('{"type":5}', "unknown message type"),
    ('{"kind":"key"}', "unknown message type"),
    ('{"type":"key","key":1,"down":true,"shift":true}', "unknown key"),
    ('{"type":"reset","now":1}', "unknown key"),
    ('{"type":"key","key":1}', "needs down"),
    ('{"type":"key","key":"1","down":true}', "integer in 0..15"),
    ('{"type":"key","key":16,"down":true}', "integer in 0..15"),
    ('{"type":"key","key":-1,"down":true}', "integer in 0..15"),
    ('{"type":"key","key":1.0,"down":true}', "integer in 0..15"),
    ('{"type":"key","key":true,"down":true}', "integer in 0..15"),
    ('{"type":"key","key":1,"down":1}', "true or false"),
    ('{"type":"key","key":1,"down":true,"seq":-4}', "seq"),
    ('{"type":"key","key":1,"down":true,"seq":1e400}', "seq"),
    ('{"type":"pause","paused":"yes"}', "true or false"),
    ('{"type":"speed","speed":2}', "speed must be"),
    ('{"type":"speed","speed":"1"}', "speed must be"),
    ('{"type":"speed","speed":true}', "speed must be"),
    ('{"type":"seat","seat":2,"player":"human"}', "integer in 0..1"),
    ('{"type":"seat","seat":0,"player":"god"}', "player must be"),
    ('{"type":"seat","seat":0,"player":["human"]}', "player must be"),
    ("x" * 2000, "too long"),
    ('{"type":"reset","pad":"' + "é" * 600 + '"}', "too long"),
    (b'{"type":"reset"}', "only text"),
    ("[" * 5000 + "]" * 5000, "too long"),
])
def test_parse_refuses_bad_messages(data, why):
    with pytest.raises(protocol.ProtocolError, match=why):
        protocol.parse(data)


def test_rate_limit_refuses_the_excess_and_spots_a_flood():
    now = [0.0]
    limit = protocol.RateLimit(rate=10, burst=20, disconnect_after=50, clock=lambda: now[0])
    assert sum(limit.allow() for _ in range(100)) == 20 and limit.refused == 80 and limit.flooding
    now[0] += 1.5  # a second and a half later: the bucket has refilled, the window is new
    assert limit.allow() and not limit.flooding


# --- the live server ---------------------------------------------------------------------------

def test_page_gets_the_game_and_frames_at_60_per_second(live):
    """The server keeps 60 frames a second (15 steps of 4 frames) for one player."""
    async def main():
        async with aiohttp.ClientSession() as client:
            async with await connect(client, live) as ws:
                hello = await receive_json(ws, "hello")
                state = await receive_json(ws, "state")
                first = await receive_json(ws, "frame")
                start, steps, last = time.perf_counter(), 0, first
                while time.perf_counter() - start < 3.0:
                    last = await receive_json(ws, "frame")
                    steps += 1
                return hello, state, first, last, steps / (time.perf_counter() - start)

    hello, state, first, last, steps_per_s = run(main())
    assert hello["game"] == GAME and hello["width"] == 64 and hello["height"] == 32
    assert hello["frames_per_step"] == 4 and hello["players"][0] == "human"
    assert len(hello["palette"]) == 4 and hello["keyboard"]["q"] == 4 and hello["keyboard"]["v"] == 15
    assert state["speed"] == 1.0 and state["paused"] is False
    assert len(__import__("base64").b64decode(first["frames"])) == 4 * 32 * 64
    server_fps = live.call(live.server.session.frames_per_second)
    print(f"\nserver: {steps_per_s:.2f} steps/s received by a client = {4 * steps_per_s:.1f} frames/s; "
          f"the session's own clock: {server_fps:.1f} frames/s; step compute median "
          f"{1000 * np.median(live.server.session.step_seconds):.2f} ms")
    assert 13.5 <= steps_per_s <= 15.5 and 54.0 <= server_fps <= 61.0  # 60 frames/s, a 10% margin for a loaded CI machine
    assert last["step"] > first["step"]


def test_keys_pause_step_reset_and_speed(live):
    session = live.server.session
    keys = session.seat_keys[0]

    async def main():
        async with aiohttp.ClientSession() as client:
            async with await connect(client, live) as ws:
                await receive_json(ws, "frame")
                await ws.send_str(json.dumps({"type": "key", "key": keys[1], "down": True, "seq": 41}))
                frame = await receive_json(ws, "frame")
                while frame["seq"] < 41:
                    frame = await receive_json(ws, "frame")
                assert frame["actions"] == [2]
                await ws.send_str(json.dumps({"type": "key", "key": keys[1], "down": False, "seq": 42}))
                await ws.send_str(json.dumps({"type": "pause", "paused": True}))
                assert (await receive_json(ws, "state"))["paused"]
                await asyncio.sleep(0.3)
                before = live.call(lambda: session.step_count)
                await asyncio.sleep(0.3)
                assert live.call(lambda: session.step_count) == before  # paused: nothing moves
                await ws.send_str(json.dumps({"type": "step"}))
                stepped = await receive_json(ws, "frame")
                assert stepped["step"] == before + 1 and stepped["actions"] == [0]
                episode = stepped["episode"]
                await ws.send_str(json.dumps({"type": "reset"}))
                reset = await receive_json(ws, "frame")
                assert (reset["episode"], reset["step"], reset["seed"]) == (episode + 1, 0, 3 + episode + 1)
                assert reset["return"] == [0.0]
                await ws.send_str(json.dumps({"type": "speed", "speed": 0.25}))
                assert (await receive_json(ws, "state"))["speed"] == 0.25
                await ws.send_str(json.dumps({"type": "pause", "paused": False}))
                await receive_json(ws, "state")
                start = time.perf_counter()
                await receive_json(ws, "frame")
                await receive_json(ws, "frame")
                await receive_json(ws, "frame")
                slow = (time.perf_counter() - start) / 2  # two periods between the three frames
                await ws.send_str(json.dumps({"type": "speed", "speed": 1}))
                await receive_json(ws, "state")
                return slow

    slow = run(main())
    assert 0.2 < slow < 0.4  # a step every 4 / 60 / 0.25 s = 0.267 s


@pytest.mark.parametrize("payload", [
    "not json at all", "[]", "null", '{"type":"key","key":"4","down":true}', '{"type":"key","key":99,"down":true}',
    '{"type":"pause","paused":1}', '{"type":"teleport","x":3}', '{"type":"key","key":4,"down":true,"ctrl":true}',
    '{"type":"speed","speed":100}', '{"type":"seat","seat":0,"player":"scripted"}',  # Dodge has no scripted player
    "x" * 5000,
])
def test_bad_messages_are_refused_and_the_connection_goes_on(live, payload):
    async def main():
        async with aiohttp.ClientSession() as client:
            async with await connect(client, live) as ws:
                await receive_json(ws, "frame")
                await ws.send_str(payload)
                error = await receive_json(ws, "error")
                await ws.send_str(json.dumps({"type": "pause", "paused": True}))
                assert (await receive_json(ws, "state"))["paused"] is True
                await ws.send_str(json.dumps({"type": "pause", "paused": False}))
                await receive_json(ws, "state")
                return error

    refused_before = len(live.server.refused)
    error = run(main())
    assert error["message"] and len(live.server.refused) > refused_before


def test_binary_and_huge_messages(live):
    async def main():
        async with aiohttp.ClientSession() as client:
            async with await connect(client, live) as ws:
                await receive_json(ws, "frame")
                await ws.send_bytes(b"\x00\xff" * 100)
                assert "only text" in (await receive_json(ws, "error"))["message"]
                await ws.send_str('{"type":"reset","x":"' + "a" * 200_000 + '"}')  # past aiohttp's limit
                while True:
                    msg = await ws.receive(timeout=5)
                    if msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.CLOSING):
                        break
                return ws.close_code

    assert run(main()) == 1009  # message too big: this connection closed...
    run(still_serving(live))     # ...and the server serves the next one
    assert any("too big" in why for why in live.server.refused)


def test_a_flood_is_refused_then_cut_off_and_the_server_survives(live):
    async def main():
        async with aiohttp.ClientSession() as client:
            async with await connect(client, live) as ws:
                await receive_json(ws, "frame")
                message = json.dumps({"type": "key", "key": 4, "down": True})
                for _ in range(5000):
                    await ws.send_str(message)
                while True:
                    msg = await ws.receive(timeout=10)
                    if msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.CLOSING):
                        return ws.close_code

    assert run(main()) == 1008
    assert any(why.startswith("flood") for why in live.server.refused)
    live.call(lambda: live.server.session.held.clear())
    run(still_serving(live))


@pytest.mark.parametrize("headers", [{"Origin": "http://evil.example"}, {"Origin": "null"}, {},
                                     {"Origin": "http://127.0.0.1:1"}])
def test_websocket_from_another_origin_is_refused(live, headers):
    async def main():
        async with aiohttp.ClientSession() as client:
            with pytest.raises(aiohttp.WSServerHandshakeError) as info:
                await client.ws_connect(live.url + "ws", headers=headers)
            return info.value.status

    assert run(main()) == 403
    assert any("origin" in why for why in live.server.refused)
    run(still_serving(live))


def test_serves_only_the_page_its_files_and_the_game(live):
    async def main():
        async with aiohttp.ClientSession() as client:
            out = {}
            for path in ("", "static/play.js", "static/play.css", "static/../server.py", "static/index.html",
                         "static/%2e%2e%2fserver.py", "etc/passwd", "favicon.ico", "static/", "ws"):
                async with client.get(live.url + path) as response:
                    out[path] = (response.status, response.headers.get("Content-Security-Policy", ""))
            async with client.post(live.url, data=b"x") as response:
                out["POST"] = (response.status, "")
            async with client.get(live.url, headers={"Host": "evil.example"}) as response:
                out["rebinding"] = (response.status, "")
            return out

    out = run(main())
    assert out[""][0] == 200 and "script-src 'self'" in out[""][1] and "default-src 'none'" in out[""][1]
    assert out["static/play.js"][0] == 200 and out["static/play.css"][0] == 200
    for path in ("static/../server.py", "static/index.html", "static/%2e%2e%2fserver.py", "etc/passwd",
                 "favicon.ico", "static/"):
        assert out[path][0] == 404, path
    assert out["ws"][0] in (400, 403)   # a plain GET without an Origin: no WebSocket
    assert out["POST"][0] in (403, 405) and out["rebinding"][0] == 403


def test_a_second_page_takes_over(live):
    async def main():
        async with aiohttp.ClientSession() as client:
            first = await connect(client, live)
            await receive_json(first, "frame")
            second = await connect(client, live)
            await receive_json(second, "hello")
            while True:
                msg = await first.receive(timeout=5)
                if msg.type in (aiohttp.WSMsgType.CLOSE, aiohttp.WSMsgType.CLOSED, aiohttp.WSMsgType.CLOSING):
                    break
            await receive_json(second, "frame")
            code = first.close_code
            await second.close()
            return code

    assert run(main()) == 4000


# --- sessions without a server -----------------------------------------------------------------

def test_session_keys_map_to_actions_latest_pressed_first():
    session = Session(GAME, seed=0)
    left, right = session.seat_keys[0][:2]
    session.key(left, True)
    assert session.human_action(0) == 1
    session.key(right, True)
    assert session.human_action(0) == 2   # the latest pressed wins while both are held
    session.key(right, False)
    assert session.human_action(0) == 1
    session.key(0xF, True)                # a key the game does not use: no change
    assert session.human_action(0) == 1
    session.key(left, False)
    session.key(0xF, False)
    assert session.human_action(0) == 0
    session.close()


def test_two_player_session_seats_and_players():
    from octax_gym import MultiAgentVectorEnv

    session = Session("Duel", seed=5)
    assert session.two_player and session.players == ["human", "scripted"]
    assert session.available_players() == ["human", "scripted", "random"]
    hello = session.hello()
    assert [seat["name"] for seat in hello["seats"]] == ["left paddle", "right paddle"]
    assert [a["keyboard"] for a in hello["seats"][0]["actions"]] == ["1", "Q"]   # keys 1, 4
    assert [a["keyboard"] for a in hello["seats"][1]["actions"]] == ["4", "R"]   # keys C, D
    session.key(0x4, True)
    actions = [session.step()["actions"] for _ in range(6)]
    assert all(a[0] == 2 for a in actions)
    session.set_player(0, "random")
    session.set_player(1, "human")
    session.key(0xD, True)
    actions += [session.step()["actions"] for _ in range(20)]
    assert all(a[1] == 2 for a in actions[6:]) and len({a[0] for a in actions[6:]}) > 1
    with pytest.raises(ValueError, match="not available"):
        session.set_player(0, "agent")
    history = [record.actions for record in session.history]
    # The env stepped alone with the logged actions from the same seed gives the same screens.
    env = MultiAgentVectorEnv("Duel", 1, autoreset_mode="disabled")
    obs, _ = env.reset(seed=5)
    for a in history:
        obs, *_ = env.step(np.array([a], np.int32))
    assert np.array_equal(session.frames(), np.asarray(obs[0, 0, :4]))
    session.close()
    env.close()
