"""One seat of a two-player game against a fixed opponent: the single-agent view that SB3,
TorchRL and any one-agent Gymnasium code train on unchanged.

    env = gymnasium.make("octax/SpaceRacer-v0", opponent="scripted")            # learner = seat 0
    env = gymnasium.make("octax/Duel-v0", opponent="random", seat=1)           # learner = player 2
    envs = gymnasium.make_vec("octax/Duel-v0", num_envs=64, opponent="scripted")
    env = gymnasium.make("octax/Duel-v0", opponent=lambda obs: my_policy(obs))  # any function

`opponent=` (with `seat=`, the learner's side, 0 or 1) is a keyword of `OctaxEnv` and
`OctaxVectorEnv`; it turns the env into the two-player env (`octax_core.make_multi`) seen from one
seat, run by the same compiled step as every other env (`octax_gym.step.compiled_step`):

* opponents: the core's table of players (`octax_core.env.players`), inside the jitted step:
  "noop" (holds no key), "random" (uniform over the actions open to it now: on a turn-based
  game's other turns that is no-op alone), "scripted" (the game's own bot,
  `Seats.scripted_policy`, which reads the machine state) and "eps<p>", e.g. "eps0.25" (the
  scripted bot with a random action with probability p: the ladder's rungs); or
  a function obs -> action, called on the host before each step with the opponent's own
  observation (its player plane included): one observation (F+1, H, W) -> one int for
  `OctaxEnv`, a batch (num_envs, F+1, H, W) -> num_envs ints for `OctaxVectorEnv`, in the env's
  backend type (numpy, JAX or torch). An SB3 model plays as `lambda obs: model.predict(obs)[0]`.
  A function's action outside 0..n-1 raises `InvalidActionError`; one its turn closes is played
  as no-op (a turn-based game's opponent moves on its own turns only).
* observation: the learner's own, uint8 (frames_per_step + 1, H, W): the step's screens, then
  the player plane (0 everywhere in seat 0, `obs_scale` in seat 1), as in the multi-agent env,
  so one policy can be trained or evaluated in either seat and still tell which side it plays.
* reward: the learner's own (the change of its seat's score); terminated and truncated are the
  game's (one machine, one episode).
* info: score (the learner's), lives (the learner's: a game's count is player 1's, so seat 1 gets
  -1, NO_LIVES), episode_step, current_player (the seat to move, -1 in a
  simultaneous game) and `action_mask` (int8, (n,), as Gymnasium's `sample(mask=)` takes): the actions open to the learner now. In a
  turn-based game that is no-op alone while the opponent moves; any other action then, or one
  the game's `legal_fn` closes, raises `IllegalMoveError` (before the step for host actions,
  deferred for device ones, as out-of-range actions: `octax_gym.step.action_check`). `OctaxEnv`
  also has `action_masks()`, the method sb3-contrib's MaskablePPO reads.

A game that is not a one-player env (`GameSpec.solo` False: a turn-based game that waits for its
second player) is registered with Gymnasium too, but must be given an opponent:
`gymnasium.make("octax/<Game>-v0")` alone raises `OpponentRequiredError`.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable, Optional

import jax
import jax.numpy as jnp

from octax_core.env import players
from octax_core.env.games import GameSpec, list_games
from octax_gym.envs.choices import UnknownOptionError

OPPONENTS = tuple(players.PLAYERS)  # the opponents that run inside the jitted step (and "eps<p>")
EPS_HINT = "'eps<p>' (the scripted player, a random action with probability p)"
SEATS = (0, 1)
OPPONENT_STREAM = 0x0990  # folded into a step's key for the random opponent's draw


class OpponentRequiredError(ValueError):
    """A two-player game that is not a one-player env was made without `opponent=`."""


@dataclasses.dataclass(frozen=True)
class View:
    """What the compiled step needs of a single-agent view: the learner's seat and the kind of
    opponent (a name of the players' table, or "callable": actions come from the host)."""

    seat: int
    opponent: str

    @property
    def other(self) -> int:
        return 1 - self.seat


def resolve(opponent: Any, seat: Any, spec: GameSpec) -> tuple[Optional[View], Optional[Callable]]:
    """The view (None for a plain one-player env) and the host function of an `opponent=` keyword.

    Raises:
        OpponentRequiredError: no opponent for a game that is not a one-player env.
        UnknownOptionError: an unknown opponent name or a seat other than 0 and 1.
        ValueError: an opponent for a one-player game, `seat=` without an opponent, or
            "scripted" for a game without a scripted policy.
    """
    if opponent is None:
        if not spec.solo:
            raise OpponentRequiredError(
                f"{spec.id} is played by two (its other seat must move for the game to go on): pass "
                f"opponent= ({', '.join(map(repr, OPPONENTS))} or a function obs -> action), e.g. "
                f"gymnasium.make('octax/{spec.base_id}-v{spec.version}', opponent='random'); or play both seats with "
                f"octax_gym.MultiAgentVectorEnv or octax_gym.pettingzoo")
        if not (isinstance(seat, int) and not isinstance(seat, bool) and seat == 0):
            raise ValueError(f"seat={seat!r} picks the learner's side against an opponent: pass opponent= too")
        return None, None
    if spec.seats is None:
        raise ValueError(f"{spec.id} is a one-player game; opponent= is for the two-player games: "
                         f"{', '.join(list_games(players=2))}")
    if isinstance(seat, bool) or seat not in SEATS:
        raise UnknownOptionError("seat", seat, SEATS, f"(the learner's side: 0 = {spec.seats.names[0]}, "
                                 f"1 = {spec.seats.names[1]})")
    seat = int(seat)
    if callable(opponent):
        return View(seat, "callable"), opponent
    eps = players.eps_of(opponent)
    if not isinstance(opponent, str) or (opponent not in OPPONENTS and eps is None):
        raise UnknownOptionError("opponent", opponent, OPPONENTS, f"{EPS_HINT}, or a function obs -> action")
    if (opponent == "scripted" or eps is not None) and spec.seats.scripted_policy is None:
        raise ValueError(f"{spec.id} has no scripted policy (Seats.scripted_policy), so no {opponent!r}; "
                         f"opponents: 'random', 'noop' or a function obs -> action")
    return View(seat, players.check_player(opponent, spec)), None


def actions_of_both(env, view: View, step_keys: jax.Array, state, learner: jax.Array,
                    given: Optional[jax.Array]) -> jax.Array:
    """Traced: the (num_envs, 2) actions of a step, the learner's in its seat's column and the
    opponent's in the other, given by the host (a function's) or played here by the table's
    player from the machine state, the actions open to it now and its own draw of the step keys.
    The table's players read no observation (the opponent's is not made before its move): None."""
    if view.opponent == "callable":
        theirs = given
    else:
        player = players.make_player(view.opponent, env.spec, env.mirrored)
        open_now = jax.vmap(env.legal_action_mask)(state)[:, view.other]
        keys = jax.vmap(lambda key: jax.random.fold_in(key, OPPONENT_STREAM))(step_keys)
        theirs = jax.vmap(player, in_axes=(None, 0, None, 0, None, 0))(None, keys, None, state, jnp.int32(view.other),
                                                                       open_now)
    theirs = jnp.asarray(theirs, jnp.int32)
    return jnp.stack([learner, theirs] if view.seat == 0 else [theirs, learner], axis=1)


# info["lives"] of a seat whose lives the game does not count (as the envs' info says without lives_fn).
NO_LIVES = -1


def learner_info(info: dict, seat: int) -> dict:
    """The learner's part of a two-player info (batched or not): its score, its lives, the shared
    counts, the seat to move, and its `action_mask`. A game's `lives_fn` counts player 1's lives
    (seat 0's), so seat 1 is told NO_LIVES rather than its opponent's count."""
    out = {name: value for name, value in info.items() if name not in ("score", "legal_action_mask")}
    out["score"] = info["score"][..., seat]
    if seat != 0 and "lives" in info:
        out["lives"] = jnp.full_like(info["lives"], NO_LIVES)
    out["action_mask"] = info["legal_action_mask"][..., seat, :]
    return out


def single_env_function(function: Callable) -> Callable:
    """A function of one observation -> one action, as a function of a batch of one (`OctaxEnv`)."""
    def batched(observations):
        return [function(observations[0])]

    batched.__wrapped__ = function
    return batched
