"""The play page's WebSocket protocol: what the page may send, checked before anything acts on it.

Client -> server, one JSON object per text message (at most `MAX_MESSAGE_BYTES` bytes):

    {"type": "key", "key": 0..15, "down": true|false, "seq": n}   a CHIP-8 key pressed or released
    {"type": "pause", "paused": true|false}
    {"type": "step"}                                          one env step while paused
    {"type": "reset"}                                         a new episode (the next seed)
    {"type": "speed", "speed": 1 | 0.5 | 0.25 | 0.125}       1 = 60 frames a second
    {"type": "seat", "seat": 0|1, "player": "human"|"agent"|"scripted"|"random"}

`seq` (optional, an int) numbers the page's key events; each step message says the last one the
step had seen, which is how the page times a key press to the frame that shows it.

Server -> client: "hello" (the game: palette, screen size, actions and their keys, seats,
players, speeds), "frame" (one env step: its frames as palette indices, base64, row-major
(frames, H, W); score, lives, reward, episode return, step, actions, seq), "state" (paused,
speed, seats), "error" (a refused message, said once per second at most).

Anything else (not JSON, not an object, an unknown type or key, a wrong value type, a value out
of range, a binary message, one too big) raises `ProtocolError`; the server logs it, tells the
page, and goes on. A page sending faster than `RateLimit` allows has the excess refused, and one
that floods far past it is disconnected.
"""

from __future__ import annotations

import dataclasses
import json
import time
from typing import Any, Optional

MAX_MESSAGE_BYTES = 1024      # the longest valid message is under 100 bytes
MAX_SEQ = 2**53 - 1           # JavaScript's largest exact integer
SPEEDS = (1.0, 0.5, 0.25, 0.125)
# The page's players: a human, the agent file, and the core's table of players
# (`octax_core.env.players`) the page offers: the game's bot and uniform random.
TABLE_PLAYERS = ("scripted", "random")
PLAYERS = ("human", "agent", *TABLE_PLAYERS)
MESSAGE_KEYS = {
    "key": {"type", "key", "down", "seq"},
    "pause": {"type", "paused"},
    "step": {"type"},
    "reset": {"type"},
    "speed": {"type", "speed"},
    "seat": {"type", "seat", "player"},
}
REQUIRED_KEYS = {
    "key": {"key", "down"},
    "pause": {"paused"},
    "speed": {"speed"},
    "seat": {"seat", "player"},
}


class ProtocolError(ValueError):
    """A message the server refuses; its text says why (and is safe to send back and to log)."""


@dataclasses.dataclass(frozen=True)
class Message:
    type: str
    key: Optional[int] = None
    down: Optional[bool] = None
    seq: Optional[int] = None
    paused: Optional[bool] = None
    speed: Optional[float] = None
    seat: Optional[int] = None
    player: Optional[str] = None


def parse(data: Any) -> Message:
    """One WebSocket text message -> a checked `Message`; raises `ProtocolError` otherwise."""
    if not isinstance(data, str):
        raise ProtocolError("only text messages (JSON) are accepted")
    if len(data) > MAX_MESSAGE_BYTES or len(data.encode("utf-8", "replace")) > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"message too long ({len(data)} characters; at most {MAX_MESSAGE_BYTES} bytes)")
    try:
        obj = json.loads(data, parse_constant=_no_constant)
    except (ValueError, RecursionError) as exc:
        raise ProtocolError(f"not JSON: {str(exc)[:80]}") from None
    if not isinstance(obj, dict):
        raise ProtocolError(f"a message is a JSON object, got {type(obj).__name__}")
    kind = obj.get("type")
    if not isinstance(kind, str) or kind not in MESSAGE_KEYS:
        raise ProtocolError(f"unknown message type {_short(kind)}; known: {', '.join(MESSAGE_KEYS)}")
    unknown = set(obj) - MESSAGE_KEYS[kind]
    if unknown:
        raise ProtocolError(f"unknown key(s) for {kind!r}: {', '.join(_short(k) for k in sorted(unknown))}")
    missing = REQUIRED_KEYS.get(kind, set()) - set(obj)
    if missing:
        raise ProtocolError(f"{kind!r} needs {', '.join(sorted(missing))}")
    fields: dict[str, Any] = {"type": kind}
    if kind == "key":
        fields["key"] = _int(obj, "key", 0, 15)
        fields["down"] = _bool(obj, "down")
        if "seq" in obj:
            fields["seq"] = _int(obj, "seq", 0, MAX_SEQ)
    elif kind == "pause":
        fields["paused"] = _bool(obj, "paused")
    elif kind == "speed":
        speed = obj["speed"]
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or float(speed) not in SPEEDS:
            raise ProtocolError(f"speed must be one of {', '.join(map(str, SPEEDS))}, got {_short(speed)}")
        fields["speed"] = float(speed)
    elif kind == "seat":
        fields["seat"] = _int(obj, "seat", 0, 1)
        player = obj["player"]
        if not isinstance(player, str) or player not in PLAYERS:
            raise ProtocolError(f"player must be one of {', '.join(PLAYERS)}, got {_short(player)}")
        fields["player"] = player
    return Message(**fields)


def _int(obj: dict, name: str, low: int, high: int) -> int:
    value = obj[name]
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ProtocolError(f"{name} must be an integer in {low}..{high}, got {_short(value)}")
    return value


def _bool(obj: dict, name: str) -> bool:
    value = obj[name]
    if not isinstance(value, bool):
        raise ProtocolError(f"{name} must be true or false, got {_short(value)}")
    return value


def _no_constant(name: str):
    raise ValueError(f"{name} is not JSON")


def _short(value: Any) -> str:
    """A value for a log line or an error message: repr'd (no raw control characters), cut short."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


class RateLimit:
    """A token bucket: `rate` messages a second on average, bursts of `burst`. `allow()` says
    whether one more message may be taken now; `flooding` whether the refusals in the last second
    passed `disconnect_after` (the server then closes the connection)."""

    def __init__(self, rate: float = 120.0, burst: float = 240.0, disconnect_after: int = 2000,
                 clock=time.monotonic):
        self.rate, self.burst, self.disconnect_after, self._clock = rate, burst, disconnect_after, clock
        self._tokens, self._last = burst, clock()
        self.refused = 0            # in all
        self._window_start, self._window_refused = self._last, 0

    def allow(self) -> bool:
        now = self._clock()
        self._tokens = min(self.burst, self._tokens + (now - self._last) * self.rate)
        self._last = now
        if now - self._window_start >= 1.0:
            self._window_start, self._window_refused = now, 0
        if self._tokens >= 1.0:
            self._tokens -= 1.0
            return True
        self.refused += 1
        self._window_refused += 1
        return False

    @property
    def flooding(self) -> bool:
        return self._window_refused > self.disconnect_after
