"""The one table of players: who can sit at a seat of a game, as traced functions of one game.

    act = make_player("eps0.25", get_spec("Cycles"))
    action = act(params, key, obs, state, seat, legal)      # int32 (), one game, one seat

Every player has that one signature, so that any of them, and a network (whose `params` are its
weights: `octax_gym.train` writes that player), fills a seat of the same compiled match
(`octax_core.env.ladder`) or step (`octax_gym.opponent`), and a match compiled once serves every
checkpoint: the params are an argument, not a constant. For one game and one seat:

- params: the player's weights; the table's players ignore them (pass anything, None included).
- key: a PRNG key, the player's own draw for this step.
- obs: the seat's observation, (frames_per_step + 1, H, W) uint8 for a two-player game
  (`MultiEnv`: its player plane included); a one-player env's (frames_per_step, H, W).
- state: the game's `EnvState` (the scripted players read its machine, as a bot would).
- seat: int32 (), 0 or 1; traced, so one compiled function plays either side.
- legal: bool (num_actions,), the actions open to the seat now (`MultiEnv.legal_action_mask`).

Batch with `jax.vmap` (params unbatched: `in_axes=(None, 0, 0, 0, 0, 0)`).

The table (`PLAYERS`, and `eps<p>` names):

- "random": uniform over the seat's legal actions (on a turn-based game's other turns that is
  no-op alone).
- "noop": action 0, no key held.
- "scripted": the game's own bot, `Seats.scripted_policy` (two-player games that have one).
- "eps<p>", e.g. "eps0.25": the scripted action, replaced with probability p by a uniform legal
  random one; eps0 is "scripted", eps1 is "random". The issue-41 measurements showed why these
  grade a ladder: on Cycles the scripted player with 50%, 25%, 10% random actions each beats
  the one below in most games (docs/multiplayer.md, "The ladder").
"""

from __future__ import annotations

import re
from typing import Any, Callable, Optional

import jax
import jax.numpy as jnp

from octax_core.env.games import GameSpec
from octax_core.validate import check_probability

# (params, key, obs, state, seat, legal) -> int32 action; see the module docstring.
Player = Callable[[Any, jax.Array, jax.Array, Any, jax.Array, jax.Array], jax.Array]

EPS_PREFIX = "eps"
_EPS_NAME = re.compile(r"eps(\d+(\.\d*)?|\.\d+)")


def noop(params, key, obs, state, seat, legal) -> jax.Array:
    """Action 0: no key held (always legal)."""
    return jnp.int32(0)


def uniform(params, key, obs, state, seat, legal) -> jax.Array:
    """Uniform over the legal actions (`legal` is never empty: no-op is always open)."""
    return jax.random.categorical(key, jnp.where(legal, 0.0, -jnp.inf)).astype(jnp.int32)


def scripted(spec: GameSpec, mirrored: bool = False) -> Player:
    """The game's `Seats.scripted_policy` for a traced seat: the policy takes its seat as a Python
    int, so both seats' actions are computed and the seat's one kept (a bot is a few compares).

    The bot reads the machine and answers in the game's own actions; in an env made with
    `mirror=True` seat 1 plays the mirror image's actions (the env maps them back), so there
    seat 1's answer is mapped through `Seats.mirror_actions` (its own inverse) first."""
    policy = _scripted_policy(spec, "scripted")
    seat_action = jnp.asarray([range(len(spec.seats.action_keys[0]) + 1),
                               spec.seats.mirror_actions if mirrored else range(len(spec.seats.action_keys[0]) + 1)],
                              jnp.int32)

    def act(params, key, obs, state, seat, legal):
        both = jnp.stack([seat_action[s, jnp.asarray(policy(state.machine, s), jnp.int32)] for s in (0, 1)])
        return both[jnp.asarray(seat, jnp.int32)]
    return act


def eps_scripted(spec: GameSpec, eps: float, mirrored: bool = False) -> Player:
    """The scripted action, replaced with probability `eps` by `uniform`'s: eps 0 is `scripted`
    (the coin never falls below 0), eps 1 is `uniform` on the same draw (`pick`)."""
    eps = check_probability("eps", eps)
    bot = scripted(spec, mirrored)

    def act(params, key, obs, state, seat, legal):
        coin, pick = jax.random.split(key)
        return jnp.where(jax.random.uniform(coin) < eps, uniform(params, pick, obs, state, seat, legal),
                         bot(params, key, obs, state, seat, legal))
    return act


# name -> spec -> player: the table every layer reads (`eps<p>` names are `eps_scripted`'s):
# octax_gym's policies (one-player envs), its opponents, the web player's seats, the tracer, the ladder.
PLAYERS: dict[str, Callable[..., Player]] = {  # (spec, mirrored=False) -> player
    "random": lambda spec, mirrored=False: uniform,
    "noop": lambda spec, mirrored=False: noop,
    "scripted": scripted,
}
SEATLESS = ("random", "noop")  # the players that read no seat, state or observation: any env's, one-player too


def player_names(spec: Optional[GameSpec] = None) -> tuple[str, ...]:
    """The table's names open to a game (all three where `spec` is None); "eps<p>" names are open
    wherever "scripted" is."""
    if spec is not None and (spec.seats is None or spec.seats.scripted_policy is None):
        return SEATLESS
    return tuple(PLAYERS)


def eps_of(name: str) -> Optional[float]:
    """p of an "eps<p>" name; None for any other name."""
    match = _EPS_NAME.fullmatch(name) if isinstance(name, str) else None
    return float(match.group(1)) if match else None


def check_player(name: Any, spec: Optional[GameSpec] = None) -> str:
    """`name`, when it names a player open to `spec` (any game's where None).

    Raises:
        ValueError: an unknown name, an eps outside [0, 1], or a scripted player for a game
            without one; the message names the valid choices.
    """
    valid = player_names(spec)
    eps = eps_of(name)
    if eps is not None:
        check_probability(f"the eps of {name!r}", eps)
        name = "scripted"
    if isinstance(name, str) and name in valid:
        return name if eps is None else f"{EPS_PREFIX}{eps:g}"
    if isinstance(name, str) and name in PLAYERS and spec is not None:
        raise ValueError(f"{spec.id} has no scripted player (Seats.scripted_policy); its players: "
                         f"{', '.join(map(repr, valid))}")
    hint = ", or 'eps<p>' (the scripted player with a random action with probability p, e.g. 'eps0.25')"
    raise ValueError(f"unknown player {name!r}; valid: {', '.join(map(repr, valid))}"
                     + (hint if "scripted" in valid else ""))


def make_player(name: str, spec: Optional[GameSpec], mirrored: bool = False) -> Player:
    """The table's player `name` ("random", "noop", "scripted", "eps<p>") for a game (`spec` None:
    any env's, for the `SEATLESS` players); `mirrored`: for an env made with `mirror=True`
    (`MultiEnv.mirrored`), where seat 1 plays the mirror image's actions.

    Raises:
        ValueError: as `check_player`.
    """
    check_player(name, spec)
    eps = eps_of(name)
    if mirrored and (spec is None or spec.seats is None or spec.seats.mirror_actions is None):
        raise ValueError(f"mirrored: {getattr(spec, 'id', None)!r} declares no mirror image (Seats.mirror_actions)")
    return eps_scripted(spec, eps, mirrored) if eps is not None else PLAYERS[name](spec, mirrored)


def _scripted_policy(spec: Optional[GameSpec], name: str):
    if spec is None or spec.seats is None or spec.seats.scripted_policy is None:
        check_player(name, spec)  # raises, naming the game's players
        raise ValueError(f"the {name!r} player is a game's own: pass its GameSpec")
    return spec.seats.scripted_policy
