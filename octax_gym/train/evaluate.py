"""Evaluation: each agent's greedy and sampled policies, each over `eval_envs` distinct episodes.

    evaluate = make_evaluate(lanes, trainer, eval_envs, max_steps)
    result = evaluate(params, key, game)    # Evaluation of (eval_envs,) returns and ended flags

Why the episodes differ: the env is deterministic by default, so `eval_envs` episodes of one
policy from one start can be one game played `eval_envs` times (Airplane's greedy evaluation once
showed std 0.00 over 16 episodes). Each evaluation episode here starts from its own reset key (its
own CXNN seed) after a uniformly drawn 0..`eval_noop_max` no-op steps (the ALE protocol, Machado
et al. 2018: 30), made once in the evaluation mix's start pool (`octax_core.env.starts`). No-op
starts rather than sticky actions: they vary where an episode begins and leave the policy's own
actions untouched, so the greedy return is the greedy policy's and not a mix of it and noise.
Training envs keep the run's own settings (no no-op starts unless asked).

Both policies play from the same starts (the same reset keys): the greedy one takes the largest
logit or Q-value among the game's actions, the sampled one is the policy as trained (PPO's
softmax, which the paper evaluates; PQN's epsilon-greedy at `eval_epsilon`, as the paper's code).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import jax
import jax.numpy as jnp

from octax_gym.train.algorithm import Trainer
from octax_gym.train.envs import Lanes


class Evaluation(NamedTuple):
    """One evaluation of one agent: per policy, each episode's return and whether it ended."""

    greedy_return: jax.Array  # (eval_envs,) float32
    greedy_ended: jax.Array  # (eval_envs,) bool: False where the step cap cut the episode short
    sampled_return: jax.Array
    sampled_ended: jax.Array


def make_evaluate(lanes: Lanes, trainer: Trainer, num_envs: int, max_steps: int) -> Callable:
    """`evaluate(params, key, game) -> Evaluation` for one agent (unjitted: the loop maps and jits it).

    Each of `num_envs` evaluation lanes plays one episode of `game` per policy, until every episode
    has ended or `max_steps` steps; a cut episode keeps its return so far.
    """
    def play(policy, params, key, game):
        reset_key, key = jax.random.split(key)
        obs, state = lanes.reset(reset_key, game, num_envs, evaluation=True)
        carry = (jnp.int32(0), key, obs, state, jnp.zeros(num_envs, jnp.float32), jnp.zeros(num_envs, jnp.bool_))

        def running(carry):
            t, _, _, _, _, ended = carry
            return (t < max_steps) & ~ended.all()

        def body(carry):
            t, key, obs, state, returns, ended = carry
            key, act_key, step_key = jax.random.split(key, 3)
            action = policy(params, act_key, obs, game)
            obs, state, reward, terminated, truncated, _ = lanes.eval_step(step_key, state, action)
            # Ended episodes stand still and pay 0 (no autoreset), so summing is safe.
            return t + 1, key, obs, state, returns + reward, ended | terminated | truncated

        _, _, _, _, returns, ended = jax.lax.while_loop(running, body, carry)
        return returns, ended

    def evaluate(params, key, game) -> Evaluation:
        # One key for both policies: the same reset keys, so the same starts.
        return Evaluation(*play(trainer.greedy, params, key, game), *play(trainer.sampled, params, key, game))

    return evaluate
