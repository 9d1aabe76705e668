"""The three autoreset modes of OctaxVectorEnv, as row-by-row tables on the Counter game.

Three envs (the batch size of test_vector_env's Counter steps, which these share), max_episode_steps=4.
Env 0 holds key 2 (action 2, +8 a step) and reaches 24 at step 3: terminated. Env 1 holds key 1
(action 1, +4 a step) and is cut off at step 4 with 16: truncated. Env 2 holds nothing (0 a step)
and is cut off at step 4 too; the tables leave it out, the masks and infos show it.
Each row is (reward, terminated, truncated, info episode_step, info score) for env 0 | env 1.
"""

from __future__ import annotations

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

from counter_game import COUNTER
from octax_gym import OctaxVectorEnv

ACTIONS = np.array([2, 1, 0])


def make(counter_rom, mode):
    return OctaxVectorEnv(COUNTER, 3, rom=counter_rom, autoreset_mode=mode, max_episode_steps=4)


def row(reward, terminated, truncated, info, env):
    return (float(reward[env]), bool(terminated[env]), bool(truncated[env]),
            int(info["episode_step"][env]), float(info["score"][env]))


def play(envs, steps):
    table, infos, observations = [], [], []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = envs.step(ACTIONS)
        table.append((row(reward, terminated, truncated, info, 0), row(reward, terminated, truncated, info, 1)))
        infos.append(info)
        observations.append(np.array(obs))
    return table, infos, observations


def test_next_step(counter_rom):
    envs = make(counter_rom, AutoresetMode.NEXT_STEP)
    assert envs.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    first_obs, _ = envs.reset(seed=0)
    table, _, observations = play(envs, 6)
    assert table == [
        ((8.0, False, False, 1, 8.0), (4.0, False, False, 1, 4.0)),
        ((8.0, False, False, 2, 16.0), (4.0, False, False, 2, 8.0)),
        ((8.0, True, False, 3, 24.0), (4.0, False, False, 3, 12.0)),
        ((0.0, False, False, 0, 0.0), (4.0, False, True, 4, 16.0)),  # env 0 resets: action ignored
        ((8.0, False, False, 1, 8.0), (0.0, False, False, 0, 0.0)),  # env 1 resets
        ((8.0, False, False, 2, 16.0), (4.0, False, False, 1, 4.0)),
    ]
    # A reset row shows the start-up screen, the same in all four frames, as reset() returns it.
    reset_obs = observations[3][0]
    assert (reset_obs == reset_obs[0]).all() and (reset_obs[0] == first_obs[0][0]).all()
    assert not (observations[2][0] == first_obs[0]).all()


def test_same_step(counter_rom):
    envs = make(counter_rom, "same_step")
    assert envs.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    envs.reset(seed=0)
    table, infos, observations = play(envs, 5)
    assert table == [
        ((8.0, False, False, 1, 8.0), (4.0, False, False, 1, 4.0)),
        ((8.0, False, False, 2, 16.0), (4.0, False, False, 2, 8.0)),
        ((8.0, True, False, 0, 0.0), (4.0, False, False, 3, 12.0)),  # env 0 ends and restarts
        ((8.0, False, False, 1, 8.0), (4.0, False, True, 0, 0.0)),   # env 1 ends and restarts
        ((8.0, False, False, 2, 16.0), (4.0, False, False, 1, 4.0)),
    ]
    # final_obs / final_info: batched, rows marked by their masks.
    masks = [(list(i["_final_obs"]), list(i["_final_info"])) for i in infos]
    assert masks == [([False, False, False],) * 2, ([False, False, False],) * 2, ([True, False, False],) * 2,
                     ([False, True, True],) * 2, ([False, False, False],) * 2]
    ended = infos[2]
    assert ended["final_obs"].shape == (3, 4, 32, 64)
    assert ended["final_info"]["score"][0] == 24 and ended["final_info"]["episode_step"][0] == 3
    assert infos[3]["final_info"]["score"][1] == 16 and infos[3]["final_info"]["episode_step"][1] == 4
    # The final observation is the last episode's (the digit drawn at y = 24 in the last frame),
    # the returned one is the new episode's start-up screen.
    last_frame = ended["final_obs"][0, -1]
    assert last_frame[24:29].any() and not last_frame[:24].any()
    assert not observations[2][0, -1, 24:29].any()


def test_disabled(counter_rom):
    envs = make(counter_rom, AutoresetMode.DISABLED)
    envs.reset(seed=0)
    table, _, observations = play(envs, 5)
    assert table == [
        ((8.0, False, False, 1, 8.0), (4.0, False, False, 1, 4.0)),
        ((8.0, False, False, 2, 16.0), (4.0, False, False, 2, 8.0)),
        ((8.0, True, False, 3, 24.0), (4.0, False, False, 3, 12.0)),
        ((0.0, True, False, 3, 24.0), (4.0, False, True, 4, 16.0)),  # env 0 stands still
        ((0.0, True, False, 3, 24.0), (0.0, False, True, 4, 16.0)),  # both stand still
    ]
    # Standing still: each frame is the screen the episode ended on.
    assert (observations[3][0] == observations[2][0][-1]).all() and (observations[4][0] == observations[3][0]).all()
    assert (observations[4][1] == observations[3][1][-1]).all()
    obs, info = envs.reset(options={"reset_mask": np.array([True, False, False])})
    assert list(info["episode_step"]) == [0, 4, 4] and list(info["score"]) == [0, 16, 0]
    assert (obs[1] == observations[4][1]).all()  # the row not reset keeps its observation
    table, _, _ = play(envs, 1)
    assert table == [((8.0, False, False, 1, 8.0), (0.0, False, True, 4, 16.0))]


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_mode_is_an_attribute_too(counter_rom, mode):
    envs = make(counter_rom, mode)
    assert envs.autoreset_mode is mode and envs.metadata["autoreset_mode"] is mode
    assert type(envs).metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP  # the class default is untouched
