"""The random rollout the mix tests compare: an episode's first steps under uniform random actions
drawn from one key, whatever env (`make`, `make_mix`) plays them."""

import jax


def random_rollout(env, params, key, num_actions, steps: int, game=None):
    """(first observation, per-step (obs, reward, terminated, truncated, score, lives, episode_step)),
    actions uniform in 0..num_actions-1; `game` forces a mix's game at the reset."""
    obs, state = env.reset(key, params) if game is None else env.reset(key, params, game=game)

    def one(carry, _):
        state, key = carry
        key, action_key, step_key = jax.random.split(key, 3)
        action = jax.random.randint(action_key, (), 0, num_actions)
        obs, state, reward, terminated, truncated, info = env.step(step_key, state, action, params)
        return (state, key), (obs, reward, terminated, truncated, info["score"], info["lives"], info["episode_step"])

    return obs, jax.lax.scan(one, (state, key), None, length=steps)[1]
