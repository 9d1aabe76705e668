"""The checks a generated game passes before it enters an archive, all candidates in one batch.

Every candidate of a round is one game of one mix (`octax_core.make_mix`, each lane running its
own program), so a round of 64 costs one compiled program, not 64. What is checked, in order
(`Verdict.reasons` names each one failed):

- assembles (checked before the batch: a candidate that does not is never run);
- runs: `frames` frames of uniform-random play (episodes restarted as they end) with every
  step's program counter inside the program, on a word the machine knows (not an unknown
  opcode, which CHIP-8 runs as a no-op), the stack no deeper than `MAX_STACK`, and no
  jump-to-itself while the game is not over (a halt);
- draws: some pixel is lit after the start;
- its keys matter: a random-play lane and a no-op lane from the same reset diverge on screen;
- its score moves under random play;
- it ends: most random-play episodes are over within `end_limit` steps;
- learnable but not trivial: a short beam search over emulator states (as docs/scores.py finds
  reference scores, with the emulator as a perfect model) beats random play over the same
  horizon by `MARGIN` (absolute) and `RATIO` (relative).

The checks at step boundaries see one instruction per step, not every one: a program can run an
unknown word between two steps and pass. The template families are built to pass them all; the
checks are for the variants whose parameters break them, and for an LLM's programs.
"""

from __future__ import annotations

import dataclasses
import functools
import tempfile
from pathlib import Path
from typing import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from octax_core.emulator.opcodes import LEVELS, OPCODES, Kind
from octax_core.emulator.state import MEMORY_OFFSET
from octax_core.env.games.spec import GameSpec

MAX_STACK = 12  # deeper than any of our programs call; a runaway recursion wraps past it
MARGIN = 2.0  # the reference must beat random play by this many points over the horizon...
RATIO = 1.5  # ...and be at least this many times its return
ENDED_SHARE = 0.5  # the share of random-play episodes that must end within end_limit steps
CHUNK = 100  # steps per jitted call
NEVER = 2**30  # max_episode_steps inside the checks


@dataclasses.dataclass(frozen=True)
class Settings:
    """How hard a round is checked. The defaults are the archive's; tests use smaller ones."""

    frames: int = 10_000  # random-play frames every candidate runs (the faults check)
    end_limit: int = 2_000  # steps within which a random-play episode must end
    random_lanes: int = 4  # random-play episodes per candidate
    horizon: int = 300  # steps the reference search and the random return are compared over
    beam: int = 16
    repeat: int = 4  # steps the search holds an action (held longer, the beam spreads wider)
    seed: int = 0


@dataclasses.dataclass(frozen=True)
class Verdict:
    """One candidate's result: accepted when `reasons` is empty."""

    reasons: tuple[str, ...]
    random_score: float  # mean return of the first random-play episode (cut at end_limit)
    random_horizon: float  # mean random-play return over the first `horizon` steps
    reference_score: float  # the search's best return over `horizon` steps

    @property
    def accepted(self) -> bool:
        return not self.reasons


@functools.lru_cache(maxsize=None)
def known_words(platform: str = "chip8") -> np.ndarray:
    """(65536,) bool: the words `platform` runs as an instruction (the first matching row of
    `OPCODES` has a kind, of this platform or an earlier one); the rest are unknown opcodes."""
    words = np.arange(0x10000)
    known = np.zeros(0x10000, bool)
    decided = np.zeros(0x10000, bool)
    for row in OPCODES:
        match = ((words & row.mask) == row.pattern) & ~decided
        known[match] = row.kind is not None and row.kind != Kind.NOP and LEVELS[row.platform] <= LEVELS[platform]
        decided |= match
    return known


def check(specs: Sequence[GameSpec], roms: Sequence[bytes], settings: Settings = Settings()) -> list[Verdict]:
    """Runs every check on every candidate (`specs[i]` plays `roms[i]`) in one mix; one Verdict each."""
    from octax_core.env.mix import make_mix

    with tempfile.TemporaryDirectory() as folder:
        paths = []
        for spec, rom in zip(specs, roms):
            path = Path(folder) / spec.rom_file
            path.write_bytes(rom)
            paths.append(path)
        # no truncation inside the checks: an episode that "ends" must end by the game's own rule
        env, params = make_mix(list(specs), roms=paths, max_episode_steps=NEVER)
    sizes = np.array([len(rom) for rom in roms])
    random = _random_play(env, params, sizes, settings)
    reference = _search(env, params, settings)
    verdicts = []
    for c in range(len(specs)):
        reasons = []
        if random["fault"][c]:
            reasons.append(f"faults under random play: {random['fault_what'][c]}")
        if not random["drew"][c]:
            reasons.append("draws nothing")
        if not random["keys_matter"][c]:
            reasons.append("its keys change nothing on screen")
        if not random["score_moved"][c]:
            reasons.append("its score never moves under random play")
        if random["ended"][c] < ENDED_SHARE:
            reasons.append(f"random play ends only {random['ended'][c]:.0%} of episodes within {settings.end_limit} steps")
        rand_h, ref = float(random["horizon_return"][c]), float(reference[c])
        if not (ref >= rand_h + MARGIN and ref >= RATIO * rand_h):
            reasons.append(f"the reference search ({ref:g}) does not beat random play ({rand_h:g}) over "
                           f"{settings.horizon} steps by {MARGIN:g} and {RATIO:g}x")
        verdicts.append(Verdict(tuple(reasons), float(random["first_return"][c]), rand_h, ref))
    return verdicts


def _random_play(env, params, sizes: np.ndarray, settings: Settings) -> dict:
    """Random play on `random_lanes` lanes per candidate, plus one no-op twin of its first lane."""
    count, lanes = len(sizes), settings.random_lanes + 1
    game = jnp.repeat(jnp.arange(count, dtype=jnp.int32), lanes)
    twin = jnp.tile(jnp.arange(lanes) == settings.random_lanes, count)
    base = jax.random.key(settings.seed)
    reset_keys = jax.random.split(jax.random.fold_in(base, 1), count * lanes)
    reset_keys = jnp.where(twin[:, None], jnp.roll(jax.random.key_data(reset_keys), settings.random_lanes, 0),
                           jax.random.key_data(reset_keys))
    reset_keys = jax.random.wrap_key_data(reset_keys)
    top = jnp.asarray(0x200 + sizes)[game]
    known = jnp.asarray(known_words(env.spec.platform))
    reset = jax.vmap(env.reset_env, in_axes=(0, None, 0))
    step = jax.vmap(env.step_env, in_axes=(0, 0, 0, None))
    _, states = reset(reset_keys, params, game)
    n = count * lanes
    carry = dict(states=states, fault=jnp.zeros(n, jnp.int32), drew=jnp.zeros(n, bool), differs=jnp.zeros(n, bool),
                 moved=jnp.zeros(n, bool), first_return=jnp.zeros(n), first_done=jnp.zeros(n, bool),
                 first_length=jnp.zeros(n, jnp.int32), horizon_return=jnp.zeros(n))

    def one(carry, t):
        states = carry["states"]
        keys = jax.random.split(jax.random.fold_in(base, t), 2 * n)
        actions = jax.vmap(lambda k: jax.random.randint(k, (), 0, env.num_actions))(keys[:n])
        actions = jnp.where(twin, 0, actions)
        obs, states, reward, terminated, _, _ = step(keys[n:], states, actions, params)
        machine = states.machine
        pc = machine.pc.astype(jnp.int32)
        word = (machine.memory[jnp.arange(n), MEMORY_OFFSET + pc].astype(jnp.int32) * 256
                + machine.memory[jnp.arange(n), MEMORY_OFFSET + pc + 1].astype(jnp.int32))
        fault = jnp.select([(pc < 0x200) | (pc >= top), ~known[word], machine.sp > MAX_STACK,
                            (word == (0x1000 | pc)) & ~terminated], [1, 2, 3, 4], 0)
        screen = obs[:, -1]
        mine = screen.reshape(count, lanes, -1)
        differs = jnp.any(mine[:, 0] != mine[:, -1], axis=-1)
        both_live = (carry["first_length"] == 0).reshape(count, lanes)
        differs = differs & both_live[:, 0] & both_live[:, -1]
        first = ~carry["first_done"]
        within = t < settings.horizon
        carry = dict(
            fault=jnp.where(carry["fault"] == 0, fault, carry["fault"]),
            drew=carry["drew"] | jnp.any(screen != 0, axis=(1, 2)),
            differs=carry["differs"] | jnp.repeat(differs, lanes),
            moved=carry["moved"] | (reward != 0),
            first_return=carry["first_return"] + jnp.where(first & (t < settings.end_limit), reward, 0.0),
            first_done=carry["first_done"] | states.done,
            first_length=jnp.where(first & states.done, t + 1, carry["first_length"]),
            horizon_return=carry["horizon_return"] + jnp.where(first & within, reward, 0.0),
            states=states)
        # an ended episode restarts on the same game, from a fresh draw (a mix's own autoreset
        # would draw another game); outside vmap, so a step where none ended skips the draw
        def restart(states):
            _, fresh = reset(jax.random.split(jax.random.fold_in(base, -t - 1), n), params, game)
            return jax.tree.map(lambda new, old: jnp.where(
                jnp.reshape(states.done, (-1,) + (1,) * (old.ndim - 1)), new, old), fresh, states)
        carry["states"] = jax.lax.cond(states.done.any(), restart, lambda states: states, states)
        return carry, None

    @jax.jit
    def chunk(carry, t0):
        return jax.lax.scan(one, carry, t0 + jnp.arange(CHUNK))[0]

    steps = max(-(-settings.frames // env.config.frames_per_step), settings.end_limit, settings.horizon)
    for t0 in range(0, steps, CHUNK):
        carry = chunk(carry, t0)
    c = {key: np.asarray(value).reshape(count, lanes) for key, value in carry.items() if key != "states"}
    random = slice(0, settings.random_lanes)
    what = {1: "the program counter left the program", 2: "an unknown opcode", 3: "the stack overflowed",
            4: "it halted (a jump to itself) while the game was on"}
    fault_code = c["fault"].max(axis=1)
    ended = (c["first_done"][:, random] & (c["first_length"][:, random] <= settings.end_limit)).mean(axis=1)
    return {"fault": fault_code > 0, "fault_what": [what.get(int(code), "") for code in fault_code],
            "drew": c["drew"].any(axis=1), "keys_matter": c["differs"][:, 0], "score_moved": c["moved"][:, random].any(axis=1),
            "ended": ended, "first_return": c["first_return"][:, random].mean(axis=1),
            "horizon_return": c["horizon_return"][:, random].mean(axis=1)}


def _search(env, params, settings: Settings) -> np.ndarray:
    """Per candidate, the best return a beam search finds within `horizon` steps from one start.

    Every beam state is tried under every action, held `repeat` steps; the `beam` children with
    the most lives, then the most points, are kept (lives first: a point bought with the last
    life ends the search's line). The emulator is the model: this is what is reachable, not
    what a policy that sees the screen learns.
    """
    count, beam, actions = env.num_games, settings.beam, env.num_actions
    reset = jax.vmap(env.reset_env, in_axes=(0, None, 0))
    step = jax.vmap(env.step_env, in_axes=(0, 0, 0, None))
    game = jnp.arange(count, dtype=jnp.int32)
    _, first = reset(jax.random.split(jax.random.key(settings.seed), count), params, game)
    states = jax.tree.map(lambda x: jnp.repeat(x, beam, 0), first)  # (count * beam, ...)
    returns = jnp.zeros(count * beam)
    step_keys = jax.random.split(jax.random.key(0), count * beam * actions)

    @jax.jit
    def expand(states, returns, best, tie_key):
        children = jax.tree.map(lambda x: jnp.repeat(x, actions, 0), states)
        held = jnp.tile(jnp.arange(actions), count * beam)

        def hold(carry, _):
            children, reward = carry
            _, children, r, _, _, info = step(step_keys, children, held, params)
            return (children, reward + r), info["lives"]
        (children, reward), lives = jax.lax.scan(hold, (children, jnp.zeros(count * beam * actions)), None,
                                                 length=settings.repeat)
        child_returns = jnp.repeat(returns, actions) + reward
        best = jnp.maximum(best, child_returns.reshape(count, -1).max(axis=1))
        value = (jnp.where(children.done, -1e6, 0.0) + 1e3 * lives[-1] + child_returns).reshape(count, -1)
        # one child per distinct machine state: equal states have equal values, so sorted by
        # (hash, value) a duplicate sits right after its twin
        hashes = jax.vmap(_state_hash)(children.machine).reshape(count, -1)
        order = jnp.lexsort((-value, hashes), axis=-1)
        sorted_hashes = jnp.take_along_axis(hashes, order, -1)
        repeated = jnp.concatenate([jnp.zeros((count, 1), bool), sorted_hashes[:, 1:] == sorted_hashes[:, :-1]], -1)
        duplicate = jnp.zeros_like(repeated).at[jnp.arange(count)[:, None], order].set(repeated)
        # ties (most steps score nothing) are broken at random, not by index: by index the beam
        # would fill with one state's descendants and lose the spread of positions it needs
        value = jnp.where(duplicate, -1e12, value + 0.5 * jax.random.uniform(tie_key, value.shape))
        _, keep = jax.lax.top_k(value, beam)
        keep = (keep + jnp.arange(count)[:, None] * beam * actions).reshape(-1)
        return jax.tree.map(lambda x: x[keep], children), child_returns[keep], best

    best = jnp.zeros(count)
    for t in range(0, settings.horizon, settings.repeat):
        states, returns, best = expand(states, returns, best, jax.random.fold_in(jax.random.key(settings.seed + 1), t))
    return np.asarray(best)


def _state_hash(machine) -> jax.Array:
    """A 32-bit hash of what makes two machines play on alike (registers, pc, stack, I, timers,
    screen, random state), to keep one of each in the beam."""
    parts = [machine.V, machine.pc, machine.I, machine.sp, machine.stack, machine.delay_timer, machine.screen,
             machine.rng]
    flat = jnp.concatenate([jnp.ravel(part).astype(jnp.uint32) for part in parts])
    weights = jnp.asarray(np.random.default_rng(0).integers(1, 2**32, flat.shape[0], dtype=np.uint64) | 1, jnp.uint32)
    return jnp.sum(flat * weights, dtype=jnp.uint32)
