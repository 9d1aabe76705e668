"""Cave Explorer: a walkthrough (found by breadth-first search over the ROM's maps and puzzle
levels) finds 14 secrets, solves the 8 puzzles and ends the game; random play finds nothing
negative."""

import jax
import jax.numpy as jnp
import numpy as np

from archive_play import play, random_policy
from octax_core.emulator.state import MEMORY_OFFSET, NO_KEY
from octax_core.env import make

# One action per key press, in order (1: key 7, 2: key 9, 3: key 5, 4: key 8, 5: key 6): the
# overworld routes between targets, each puzzle's solution and a key for each page of text.
WALKTHROUGH = ("311111333333222422223332222222222241111111422332233111111113333322222222231111133333332225"
               "111151152522222233333333334444444444444444222222222232242232244422215252251115251115113322"
               "322422222222444444434442244333333441133111122224422333442233222222222222442233222152215111"
               "522222111111522222511111511441133111122224422332251111512222251111522222522441133111121222"
               "224442222233333111444231333222444441111144442222222222444422225111115222511151133111111111"
               "111144222222222244444222222222222222222222224222232242125151251522522511125222511111252222"
               "522313114111131111111111111114442244411441111211144111111331111111122224441112522522222151"
               "15251112511522215221522152511151")


def _play_walkthrough(steps):
    """Presses each key of the walkthrough for one step and releases it the next, whenever the
    program waits at an FX0A that has seen no key yet."""
    env, params = make("CaveExplorer")
    plan = jnp.array([int(a) for a in WALKTHROUGH] + [0])

    def waiting(machine):
        pc = machine.pc.astype(jnp.int32)
        opcode_hi, opcode_lo = machine.memory[MEMORY_OFFSET + pc], machine.memory[MEMORY_OFFSET + pc + 1]
        return ((opcode_hi >> 4) == 0xF) & (opcode_lo == 0x0A) & (machine.key_wait == NO_KEY)

    def body(carry, key):
        state, index, pressed = carry
        press = ~pressed & waiting(state.machine)
        action = jnp.where(press, plan[index], 0)
        _, state, reward, terminated, _, _ = env.step(key, state, action, params)
        index = jnp.where(pressed, index + 1, index)
        return (state, index, press), (reward, terminated)

    _, state = env.reset(jax.random.key(0), params)
    keys = jax.random.split(jax.random.key(1), steps)
    (_, index, _), (rewards, terminated) = jax.jit(lambda c, k: jax.lax.scan(body, c, k))(
        (state, jnp.int32(0), jnp.bool_(False)), keys)
    return int(index), np.asarray(rewards), np.asarray(terminated)


def test_the_walkthrough_solves_every_puzzle_and_gets_out():
    index, rewards, terminated = _play_walkthrough(3200)  # the end comes at step 2,826
    assert terminated.any() and index == len(WALKTHROUGH)
    end = int(np.argmax(terminated))
    assert rewards[: end + 1].sum() == 14 + 8 and set(rewards[: end + 1]) == {0.0, 1.0}


def test_random_play_only_gains():
    played = play("CaveExplorer", random_policy(6), steps=1500, num_envs=2)
    assert (played.rewards >= 0).all() and played.rewards.max() <= 1
