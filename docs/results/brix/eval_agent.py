"""An agent of train_layout.py's runs on our Brix: greedy and sampled, with and without the
evaluation's 0..30 no-op starts, each over EPISODES episodes from distinct reset keys.

    LAYOUT=paper python eval_agent.py AGENT.msgpack [EPISODES] [MAX_STEPS]
"""
import os, sys
os.environ.setdefault("OCTAX_ROM_DIR", "/work/shared/roms/octax")
import flax.serialization, jax, jax.numpy as jnp, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import train_layout_torso  # noqa: F401  (swaps the torso when LAYOUT=paper)
import octax_core
from octax_gym.train.networks import ActorCritic, legal_actions, masked

path = sys.argv[1]
episodes = int(sys.argv[2]) if len(sys.argv) > 2 else 128
max_steps = int(sys.argv[3]) if len(sys.argv) > 3 else 2000
net = ActorCritic()
template = net.init(jax.random.key(0), jnp.zeros((1, 4, 32, 64), jnp.uint8))
params = flax.serialization.from_bytes(template, open(path, "rb").read())


def play(noop_max, greedy):
    env, env_params = octax_core.make("Brix", noop_max=noop_max)
    legal = legal_actions(env.num_actions)
    keys = jax.random.split(jax.random.key(123), episodes)
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(keys, env_params)

    def body(carry, t):
        obs, state, ret, done, key = carry
        key, act_key, step_key = jax.random.split(key, 3)
        logits = masked(net.apply(params, obs)[0], legal)
        action = jnp.argmax(logits, 1) if greedy else jax.random.categorical(act_key, logits)
        obs, state, r, term, trunc, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
            jax.random.split(step_key, episodes), state, action.astype(jnp.int32), env_params)
        return (obs, state, ret + r, done | term | trunc, key), None

    carry = (obs, state, jnp.zeros(episodes), jnp.zeros(episodes, bool), jax.random.key(7))
    (_, _, ret, done, _), _ = jax.jit(lambda c: jax.lax.scan(body, c, jnp.arange(max_steps)))(carry)
    ret, done = np.asarray(ret), np.asarray(done)
    return f"mean {ret.mean():.2f} median {np.median(ret):.1f} min {ret.min():.0f} max {ret.max():.0f} ended {done.mean():.2f}"


for noop_max in (0, 30):
    for greedy in (True, False):
        print(f"{os.path.basename(path)} noop_max={noop_max} {'greedy ' if greedy else 'sampled'}: {play(noop_max, greedy)}", flush=True)
