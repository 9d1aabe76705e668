"""The octax package's Brix (0.1.1, as its create_environment builds it) over our ROM file.

    /tmp/octaxvenv/bin/python octax_side.py [--five] POLICY:STEPS:EPISODES ...

Run in a venv of its own (pip install octax opencv-python-headless pillow). Our actions are
mapped to octax's (its no-op is its last action), so both sides play the same policies.
"""
import json, os, sys, warnings, time
warnings.filterwarnings("ignore")
import jax, jax.numpy as jnp, numpy as np
OUT = os.environ.get("OUT", ".")  # where the JSON summary goes
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from policies import POLICIES, run_requests, summarize
from octax.env import OctaxEnv
from octax.environments import brix as game

ROM = os.path.join(os.environ.get("OCTAX_ROM_DIR", "/work/shared/roms/octax"), "Brix [Andreas Gustafsson, 1990].ch8")
five_balls = "--five" in sys.argv
env = OctaxEnv(rom_path=ROM, score_fn=game.score_fn,
               terminated_fn=(lambda s: (s.V[14] == 0) | (s.V[5] == 96)) if five_balls else game.terminated_fn,
               action_set=game.action_set, startup_instructions=game.startup_instructions,
               disable_delay=game.disable_delay)
OURS_TO_OCTAX = jnp.array([2, 0, 1])  # our 0 no-op, 1 key 4, 2 key 6 -> octax's 0 key 4, 1 key 6, 2 no-op

def rollout(policy, n, T, seed):
    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    state, obs, info = jax.vmap(env.reset)(keys)
    def body(carry, t):
        state, done, k = carry
        k, *sub = jax.random.split(k, n + 1)
        a = jax.vmap(policy)(state.V, jnp.stack(sub))
        state, obs, r, term, trunc, info = jax.vmap(env.step)(state, OURS_TO_OCTAX[a])
        r = jnp.where(done, 0.0, r)
        newdone = done | term | trunc
        return (state, newdone, k), (r, newdone & ~done, state.V[:, 14], a)
    (state, done, _), (r, d, lives, acts) = jax.lax.scan(body, (state, jnp.zeros(n, bool), jax.random.PRNGKey(seed + 1)), jnp.arange(T))
    return np.asarray(r), np.asarray(d), np.asarray(lives), np.asarray(acts)

if __name__ == "__main__":
    out = {"side": "octax 0.1.1", "five_balls": five_balls}
    s0 = env.cached_reset_state
    out["start"] = {"pc": hex(int(s0.pc)), "V": [int(v) for v in s0.V], "delay": int(s0.delay_timer),
                    "lit_pixels": int(s0.display.sum()), "instructions_per_step": env.instructions_per_step * env.frame_skip,
                    "max_steps": env.max_num_steps_per_episodes, "obs_shape": list(env.pad_frame(s0.display).shape)}
    print(json.dumps(out["start"]), flush=True)
    res = run_requests(rollout, sys.argv[1:], first_actions=True)
    out["results"] = res
    tag = "five" if five_balls else "paper"
    json.dump(out, open(f"{OUT}/octax_{tag}.json", "w"), indent=1)
