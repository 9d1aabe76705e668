"""Play a game yourself in the browser: `octax-gym play GAME` (docs/play.md).

A local web server (aiohttp, the `play` extra) where the real env steps; a static page from
`static/` draws the frames in the game's palette and sends the keyboard (Octo's layout).

    from octax_gym.play import Session, PlayServer, start_in_thread
    handle = start_in_thread(Session("Brix", seed=0))   # handle.url; handle.stop()

Modules: `protocol` (the WebSocket messages and their checks), `session` (the env, seats and
episodes), `server` (the web app), `agents` (trained agents: JAX params or SB3 zips), `record`
(human episodes as a Minari dataset). Only `server` needs aiohttp.
"""

from octax_gym.play.session import KEYBOARD, Session

__all__ = ["KEYBOARD", "Session", "PlayServer", "start_in_thread"]


def __getattr__(name):  # the server imports aiohttp: only when asked for
    if name in ("PlayServer", "start_in_thread"):
        from octax_gym.play import server
        return getattr(server, name)
    raise AttributeError(name)
