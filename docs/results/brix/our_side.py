"""Our Brix (octax_core.make) under the policies of policies.py, one JSON line per policy.

    python our_side.py [--octaxpace] [--noop30] [--five] [--frozen] POLICY:STEPS:EPISODES ...

--octaxpace: the octax package's pacing (44 instructions a step, no display wait, timers zeroed);
--noop30: the evaluation's 0..30 no-op starts; --five: the whole 5-ball game (V14 == 0);
--frozen: freeze_timers alone. Without flags: `make("Brix")` as registered.
"""
import json, sys, time, dataclasses, os
os.environ.setdefault("OCTAX_ROM_DIR", "/work/shared/roms/octax")
import jax, jax.numpy as jnp, numpy as np
OUT = os.environ.get("OUT", ".")  # where the JSON summary goes
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from policies import POLICIES, run_requests, summarize
import octax_core

five = "--five" in sys.argv
frozen = "--frozen" in sys.argv
spec = octax_core.get_spec("Brix")
if five:
    spec = dataclasses.replace(spec, terminated_fn=lambda s: (s.V[14] == 0) | (s.V[5] == 96))
opts = {"freeze_timers": True} if frozen else {}
octaxpace = "--octaxpace" in sys.argv
if octaxpace:  # the octax package's pacing: 44 instructions a step, no display wait, timers zeroed, 506-instruction start
    from octax_core.emulator.quirks import Quirks
    spec = dataclasses.replace(spec, quirks=Quirks(vf_reset=False, memory_increment=False, display_wait=False, clipping=True,
                                                   shift_uses_vy=False, jump_uses_vx=False),
                               freeze_timers=True, startup=((0, 46),))
noop30 = "--noop30" in sys.argv
if noop30:
    opts["noop_max"] = 30
env, params = octax_core.make(spec, **opts)

def rollout(policy, n, T, seed):
    keys = jax.random.split(jax.random.PRNGKey(seed), n)
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    def body(carry, t):
        state, done, k = carry
        k, *sub = jax.random.split(k, 2 * n + 1)
        sub = jnp.stack(sub)
        a = jax.vmap(policy)(state.machine.V, sub[:n])
        obs, state, r, term, trunc, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(sub[n:], state, a, params)
        newdone = done | term | trunc
        return (state, newdone, k), (jnp.where(done, 0.0, r), newdone & ~done, state.machine.V[:, 14], a)
    (state, done, _), (r, d, lives, acts) = jax.jit(lambda s: jax.lax.scan(body, (s, jnp.zeros(n, bool), jax.random.PRNGKey(seed + 1)), jnp.arange(T)))(state)
    return np.asarray(r), np.asarray(d), np.asarray(lives), np.asarray(acts)

if __name__ == "__main__":
    out = {"side": "ours", "five_balls": five, "frozen": frozen, "noop_max": 30 if noop30 else 0, "octaxpace": octaxpace}
    _, s0 = env.reset(jax.random.PRNGKey(0), params)
    m = s0.machine
    out["start"] = {"pc": hex(int(m.pc)), "V": [int(v) for v in m.V], "delay": int(m.delay_timer),
                    "max_steps": int(params.max_episode_steps), "obs_shape": list(_.shape)}
    print(json.dumps(out["start"]), flush=True)
    res = run_requests(rollout, sys.argv[1:])
    out["results"] = res
    tag = ("five" if five else "paper") + ("_frozen" if frozen else "") + ("_noop30" if noop30 else "") + ("_octaxpace" if octaxpace else "")
    json.dump(out, open(f"{OUT}/ours_{tag}.json", "w"), indent=1)
