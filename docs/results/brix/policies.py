"""Policies over Brix's registers, shared by both sides. Our action ids: 0 no-op, 1 key 4 (left), 2 key 6 (right)."""
import jax, jax.numpy as jnp

def noop(V, key): return jnp.int32(0)
def left(V, key): return jnp.int32(1)
def right(V, key): return jnp.int32(2)
def rand(V, key): return jax.random.randint(key, (), 0, 3)

def follow(V, key):
    """Keep the ball's column (V6) over the paddle's middle (VC+2..VC+3); the paddle moves 2 px a loop."""
    ball = V[6].astype(jnp.int32); pad = V[12].astype(jnp.int32)
    return jnp.where(ball < pad + 2, 1, jnp.where(ball > pad + 3, 2, 0)).astype(jnp.int32)

def follow_eps(eps):
    def p(V, key):
        k1, k2 = jax.random.split(key)
        return jnp.where(jax.random.uniform(k1) < eps, rand(V, k2), follow(V, key))
    return p

POLICIES = {"noop": noop, "left": left, "right": right, "random": rand, "follow": follow,
            "follow_eps0.1": follow_eps(0.1), "follow_eps0.3": follow_eps(0.3)}

def summarize(name, rewards, dones, lengths_cap):
    """rewards, dones: (T, N) numpy; the episode is the prefix up to and including the first done."""
    import numpy as np
    T, N = rewards.shape
    rets, lens, gaps, ended = [], [], [], 0
    for n in range(N):
        d = np.nonzero(dones[:, n])[0]
        L = int(d[0]) + 1 if len(d) else T
        ended += bool(len(d))
        r = rewards[:L, n]
        rets.append(float(r.sum())); lens.append(L)
        t = np.nonzero(r)[0]
        if len(t) > 1: gaps.extend(np.diff(t).tolist())
        if len(t): gaps.append(int(t[0]) + 1)
    rets, lens = np.array(rets), np.array(lens)
    return {"policy": name, "episodes": N, "ended": ended, "mean_return": float(rets.mean()),
            "std_return": float(rets.std()), "min_return": float(rets.min()), "max_return": float(rets.max()),
            "mean_length": float(lens.mean()), "min_length": int(lens.min()), "max_length": int(lens.max()),
            "steps_per_reward": float(lens.sum() / max(rets.sum(), 1e-9)),
            "mean_steps_to_next_reward": float(np.mean(gaps)) if gaps else None,
            "frac_episodes_zero_reward": float((rets == 0).mean())}

def follow2(V, key):
    """`follow`, aware of the edges: the paddle (VC, even, 6 px) wraps at 64, so never step left of 0 or right of 58."""
    d = V[6].astype(jnp.int32) - V[12].astype(jnp.int32)
    pad = V[12].astype(jnp.int32)
    return jnp.where((d < 1) & (pad >= 2), 1, jnp.where((d > 4) & (pad <= 56), 2, 0)).astype(jnp.int32)

POLICIES["follow2"] = follow2


def run_requests(rollout, argv, first_actions=False):
    """Each `name:steps:episodes` argument of `argv`: `rollout(policy, episodes, steps, seed 0)`
    summarized and printed as one JSON line; returns the summaries."""
    import json, time
    results = []
    for name, T, n in [(a.split(":")[0], int(a.split(":")[1]), int(a.split(":")[2])) for a in argv if ":" in a]:
        t0 = time.time()
        r, d, lives, acts = rollout(POLICIES[name], n, T, 0)
        s = summarize(name, r, d, T); s["seconds"] = round(time.time() - t0, 1)
        if first_actions:
            s["first_actions_ep0"] = acts[:8, 0].tolist()
        results.append(s); print(json.dumps(s), flush=True)
    return results
