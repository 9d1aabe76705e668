"""The start-up handshake of a distributed run: the processes meet on the coordinator's port before JAX does.

JAX's own registration checks little and answers most mistakes by aborting the process (SIGABRT,
no Python exception) or not at all: ranks that disagree on the process count joined as the smaller
run. So `meet` runs first, over plain TCP on the coordinator's address: process 0 listens on the
port JAX's coordinator will take, greets each connection, and collects every other process's
(num_processes, process_id); once processes 1..N-1 have each come once it answers them all "ok"
and frees the port for JAX, and on the first mismatch (another count, an id given twice) or at the
timeout it answers them all with what was wrong. Each line is HANDSHAKE then one JSON object, so
a port held by another program (which greets with something else, or not at all) is told apart
within GREETING_S. A second process 0 finds the port held and reports to the holder as process 0,
so both learn of the duplicate. Every failure is a `HandshakeError` with its message ready for the user.
"""

from __future__ import annotations

import errno
import json
import os
import selectors
import socket
import time
from typing import Optional

HANDSHAKE = b"octax-gym-start-up/1 "  # every line of the handshake starts so; the rest is one JSON object
GREETING_S = 15.0  # process 0 greets at once: this long without a greeting means the port is someone else's
FAREWELL_S = 2.0  # process 0 lets the others hang up first, so the port's closed connections wait on their side
LINE_LIMIT = 4096


class HandshakeError(RuntimeError):
    """The processes could not agree on the run: the message names the mismatch."""


def meet(address: str, num_processes: int, process_id: int, timeout_s: float) -> None:
    """The handshake on the coordinator's port: process 0 holds it, the others report to it."""
    if process_id != 0:
        _report(address, num_processes, process_id, timeout_s, wait=True)
        return
    try:
        listener = _listen(address)
    except OSError as exc:
        if exc.errno != errno.EADDRINUSE:
            raise HandshakeError(f"process 0 could not listen on the coordinator's port at {address} ({exc})") from None
        try:  # another process 0 of this run holds it (it will name the duplicate), or another program does
            _report(address, num_processes, 0, timeout_s, wait=False)
        except HandshakeError as reason:
            raise HandshakeError(f"process 0 could not listen on the coordinator's port at {address}, which is in "
                                 f"use: {reason}") from None
        raise HandshakeError(f"process 0 could not listen on the coordinator's port at {address}: another process 0 "
                             f"holds it")  # one of this version would have refused this one
    with listener:
        verdict = _gather(listener, num_processes, timeout_s)
    if verdict:
        raise HandshakeError(f"process 0 of {num_processes}: {verdict} (coordinator {address})")


def _listen(address: str) -> socket.socket:
    """A listening socket where JAX's coordinator will listen: every address, the coordinator's port."""
    bind = os.environ.get("JAX_COORDINATOR_BIND_ADDRESS")
    host, port = split_address(bind) if bind else ("", split_address(address)[1])
    if host in ("", "::") and socket.has_dualstack_ipv6():
        return socket.create_server(("::", port), family=socket.AF_INET6, dualstack_ipv6=True)
    return socket.create_server((host, port))


def _gather(listener: socket.socket, num_processes: int, timeout_s: float) -> str:
    """Process 0: waits for processes 1..N-1, answers each, and returns "" or what was wrong.

    Connections that do not speak the handshake (a port scanner, a stray client) are dropped
    without failing the run; the first mismatch ends the wait at once.
    """
    deadline = time.monotonic() + timeout_s
    selector = selectors.DefaultSelector()
    selector.register(listener, selectors.EVENT_READ)
    partial: dict[socket.socket, bytes] = {}  # greeted connections whose hello is still on its way
    heard: list[socket.socket] = []  # connections that said hello: each gets the verdict
    seats: set[int] = set()
    verdict = ""
    try:
        while not verdict and len(seats) < num_processes - 1:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                missing = [str(i) for i in range(1, num_processes) if i not in seats]
                verdict = (f"process{'es' if len(missing) > 1 else ''} {', '.join(missing)} did not join within "
                           f"{timeout_s} s (were they started, with this address?)")
                break
            for key, _ in selector.select(remaining):
                if key.fileobj is listener:
                    _greet(listener, selector, partial, num_processes)
                    continue
                hello = _hello(key.fileobj, selector, partial)
                if hello is not None:
                    heard.append(key.fileobj)
                    verdict = verdict or _seat(hello, seats, num_processes)
        _answer(heard, verdict)
        _answer(list(partial), verdict or f"all {num_processes} processes had joined before this one: one process "
                                          f"too many (a process id given twice, or more than num_processes?)")
    finally:
        for conn in [*partial, *heard]:
            conn.close()
        selector.close()
    return verdict


def _greet(listener, selector, partial, num_processes) -> None:
    """Accepts a connection and greets it at once, so that a process can tell this port from another program's."""
    conn, _ = listener.accept()
    try:
        conn.sendall(_line({"num_processes": num_processes}))
    except OSError:
        conn.close()
        return
    conn.setblocking(False)
    partial[conn] = b""
    selector.register(conn, selectors.EVENT_READ)


def _hello(conn, selector, partial) -> Optional[dict]:
    """The process's hello once its line is complete; None while it is not (or when the client is dropped)."""
    try:
        chunk = conn.recv(LINE_LIMIT)
    except OSError:
        chunk = b""
    partial[conn] += chunk
    if chunk and b"\n" not in partial[conn] and len(partial[conn]) < LINE_LIMIT:
        return None
    selector.unregister(conn)
    conn.setblocking(True)
    hello = _parse(partial.pop(conn))
    if not (hello and is_int(hello.get("num_processes")) and is_int(hello.get("process_id"))):
        conn.close()
        return None
    return hello


def _seat(hello: dict, seats: set, num_processes: int) -> str:
    """Takes a process's seat; returns what is wrong with it ("" when nothing is)."""
    process_id, theirs = hello["process_id"], hello["num_processes"]
    if theirs != num_processes:
        return f"process {process_id} says the run has {theirs} processes, process 0 says {num_processes}"
    if process_id in seats or process_id == 0:
        return f"process id {process_id} is claimed by two processes"
    if not 0 < process_id < num_processes:
        return f"process id {process_id} is outside 0..{num_processes - 1}"
    seats.add(process_id)
    return ""


def _answer(members: list, verdict: str) -> None:
    """Tells every process the verdict, then waits briefly (FAREWELL_S in all) for them to hang up first."""
    for conn in members:
        try:
            conn.setblocking(True)
            conn.sendall(_line({"error": verdict} if verdict else {"ok": True}))
        except OSError:
            pass
    deadline = time.monotonic() + FAREWELL_S
    for conn in members:
        try:
            conn.settimeout(max(deadline - time.monotonic(), 0.001))
            conn.recv(1)
        except OSError:
            pass


def _report(address: str, num_processes: int, process_id: int, timeout_s: float, *, wait: bool) -> None:
    """Processes 1..N-1: says who this is to process 0 and raises what it answers, if not ok."""
    who = f"process {process_id} of {num_processes}"
    with _connect(address, timeout_s, who, wait) as conn:
        received = bytearray()  # the greeting and the answer may come in one packet
        try:
            raw = _read_line(conn, min(GREETING_S, timeout_s), received)
            got = f"it sent {raw[:40]!r}" if raw else "it hung up at once"
        except OSError as exc:
            raw, got = b"", (f"it sent nothing within {min(GREETING_S, timeout_s):g} s"
                             if isinstance(exc, TimeoutError) else str(exc))
        if not _parse(raw):
            raise HandshakeError(
                f"{who}: {address} answered but not with octax-gym's start-up handshake ({got}): another program "
                f"holds that port, or process 0 already started a run there with other processes (a process id "
                f"given twice, or more processes than num_processes?)")
        conn.sendall(_line({"num_processes": num_processes, "process_id": process_id}))
        try:  # process 0 answers within its own timeout, which started before this process connected
            answer = _parse(_read_line(conn, timeout_s + GREETING_S, received)) or {}
        except OSError as exc:
            answer = {"error": f"process 0 gave no answer ({exc})"}
    if not answer.get("ok"):
        reason = answer.get("error") or "process 0 hung up without an answer (did it stop?)"
        raise HandshakeError(f"{who}: {reason} (coordinator {address})")


def _connect(address: str, timeout_s: float, who: str, wait: bool) -> socket.socket:
    """A connection to `address`, retried until `timeout_s` when `wait` (process 0 may start later)."""
    host, port = split_address(address)
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return socket.create_connection((host, port), timeout=1.0)
        except OSError as exc:
            if not wait or time.monotonic() >= deadline:
                raise HandshakeError(
                    f"{who} could not reach the coordinator at {address} within {timeout_s} s ({exc}): is process "
                    f"0 running and reachable there?") from None
            time.sleep(0.2)


def _line(message: dict) -> bytes:
    return HANDSHAKE + json.dumps(message).encode() + b"\n"


def _parse(line: bytes) -> Optional[dict]:
    """The handshake message on `line`, or None when the line is not one."""
    if not line.startswith(HANDSHAKE) or not line.endswith(b"\n"):
        return None
    try:
        message = json.loads(line[len(HANDSHAKE):])
    except ValueError:
        return None
    return message if isinstance(message, dict) else None


def _read_line(conn: socket.socket, timeout_s: float, received: bytearray) -> bytes:
    """The peer's next line, newline included (or what came before EOF or LINE_LIMIT bytes), within `timeout_s`.

    `received` holds what came after the line, for the next call.
    """
    deadline = time.monotonic() + timeout_s
    while b"\n" not in received and len(received) < LINE_LIMIT:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise TimeoutError("timed out")
        conn.settimeout(remaining)
        chunk = conn.recv(LINE_LIMIT)
        if not chunk:
            break
        received += chunk
    end = received.find(b"\n") + 1 or len(received)
    line = bytes(received[:end])
    del received[:end]
    return line


def split_address(address) -> tuple[str, int]:
    """("host", port) from "host:port" or "[v6]:port"."""
    host, _, port = str(address).rpartition(":")
    if not host or not port.isdigit():
        raise ValueError(f"coordinator_address must be 'host:port', got {address!r}")
    if not 1 <= int(port) <= 65535:
        raise ValueError(f"the port in coordinator_address must be in 1..65535, got {int(port)}")
    return host.strip("[]"), int(port)


def is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)
