"""One seat of a two-player game against a fixed opponent: the single-agent view that SB3,
TorchRL and any one-agent Gymnasium code train on unchanged.

    env = gymnasium.make("octax/SpaceRacer-v0", opponent="scripted")            # learner = seat 0
    env = gymnasium.make("octax/Duel-v0", opponent="random", seat=1)           # learner = player 2
    envs = gymnasium.make_vec("octax/Duel-v0", num_envs=64, opponent="scripted")
    env = gymnasium.make("octax/Duel-v0", opponent=lambda obs: my_policy(obs))  # any function

`opponent=` (with `seat=`, the learner's side, 0 or 1) is a keyword of `OctaxEnv` and
`OctaxVectorEnv`; it turns the env into the two-player env (`octax_core.make_multi`) seen from one
seat, run by the same compiled step as every other env (`octax_gym.compiled_step`):

* opponents: "noop" (holds no key), "random" (uniform over the actions open to it now: on a
  turn-based game's other turns that is no-op alone), "scripted" (the game's own bot,
  `Seats.scripted_policy`, which reads the machine state), all three inside the jitted step; or
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
  deferred for device ones, as out-of-range actions: `octax_gym.action_check`). `OctaxEnv`
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

from octax_core.env.games import GameSpec, list_games
from octax_gym.choices import UnknownOptionError

OPPONENTS = ("random", "noop", "scripted")  # the opponents that run inside the jitted step
SEATS = (0, 1)
OPPONENT_STREAM = 0x0990  # folded into a step's key for the random opponent's draw


class OpponentRequiredError(ValueError):
    """A two-player game that is not a one-player env was made without `opponent=`."""


@dataclasses.dataclass(frozen=True)
class View:
    """What the compiled step needs of a single-agent view: the learner's seat and the kind of
    opponent ("random", "noop", "scripted", or "callable": actions come from the host)."""

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
                f"gymnasium.make('octax/{spec.id}-v{spec.version}', opponent='random'); or play both seats with "
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
    if not isinstance(opponent, str) or opponent not in OPPONENTS:
        raise UnknownOptionError("opponent", opponent, OPPONENTS, "or a function obs -> action")
    if opponent == "scripted" and spec.seats.scripted_policy is None:
        raise ValueError(f"{spec.id} has no scripted policy (Seats.scripted_policy); opponents: 'random', "
                         f"'noop' or a function obs -> action")
    return View(seat, opponent), None


def actions_of_both(env, view: View, step_keys: jax.Array, state, learner: jax.Array,
                    given: Optional[jax.Array]) -> jax.Array:
    """Traced: the (num_envs, 2) actions of a step, the learner's in its seat's column and the
    opponent's in the other, computed here from the machine state (scripted), the step keys
    (random) or given by the host (a function's)."""
    other = view.other
    if view.opponent == "callable":
        theirs = given
    elif view.opponent == "noop":
        theirs = jnp.zeros_like(learner)
    elif view.opponent == "scripted":
        policy = env.seats.scripted_policy
        theirs = jax.vmap(lambda machine: jnp.asarray(policy(machine, other), jnp.int32))(state.machine)
    else:  # random: uniform over the actions open to the opponent now
        open_now = jax.vmap(env.legal_action_mask)(state)[:, other]
        keys = jax.vmap(lambda key: jax.random.fold_in(key, OPPONENT_STREAM))(step_keys)
        theirs = jax.vmap(lambda key, mask: jax.random.categorical(key, jnp.where(mask, 0.0, -jnp.inf)))(keys, open_now)
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
