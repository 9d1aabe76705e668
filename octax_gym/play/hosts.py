"""Which `Host` headers the play server answers: the DNS-rebinding check and where it applies.

    is_loopback("127.0.0.1"), is_loopback("localhost")    # True: the check stays on
    is_loopback("0.0.0.0")                                 # False: reachable by name from afar
    answers("evil.example:8000", bind="127.0.0.1", port=8000)   # False: 403

A page of another site can rename itself to 127.0.0.1 (DNS rebinding) and reach a server on this
machine, but its requests still carry its own name in `Host`; so a server bound to loopback answers
only Host values that are loopback names of its own port. A bind beyond loopback is reached by
names this server cannot know, so there any Host is answered (and the command line warns).
"""

from __future__ import annotations

import ipaddress
import socket
from typing import Optional

LOOPBACK = ("127.0.0.1", "localhost", "[::1]", "::1")


def is_loopback(host: str) -> bool:
    """Whether `host` (an address or a name) is this machine's loopback alone (127.0.0.0/8, ::1).

    A name counts only when every address it resolves to is loopback; an unresolvable name or an
    empty one (all interfaces) does not: the check is relaxed only where the bind is reachable
    from elsewhere.
    """
    name = host.strip("[]")
    try:
        return _loopback_address(name)
    except ValueError:
        pass
    try:
        infos = socket.getaddrinfo(name, None, type=socket.SOCK_STREAM) if name else []
    except (OSError, UnicodeError):
        return False
    return bool(infos) and all(_loopback_address(info[4][0].split("%")[0]) for info in infos)


def _loopback_address(text: str) -> bool:
    address = ipaddress.ip_address(text)  # ValueError: not an address
    mapped = getattr(address, "ipv4_mapped", None)  # ::ffff:127.0.0.1 (Python < 3.13 calls it not loopback)
    return (mapped or address).is_loopback


def answers(host_header: Optional[str], *, bind: str, port: Optional[int]) -> bool:
    """Whether a server bound to loopback address `bind` on `port` answers this Host header."""
    if not host_header or port is None:
        return False
    name, _, header_port = host_header.rpartition(":")
    return header_port == str(port) and name in LOOPBACK + (bind, f"[{bind}]")
