"""Trained JAX agents run from their saved params: the package's network (`octax_gym.train.networks`).

`octax-gym train` saves each agent as `OUT/agents/<game>-seed<s>.msgpack` (flax serialization of
`{"params": ...}` of `ActorCritic` or `QNetwork`, 17 outputs: no-op and the 16 keys); older files
of the examples (one output per action of their game) load too, and float16 copies (committed
agents) are read back as float32. Here they are read and run by the same flax modules that trained
them, so `octax-gym play --agent` and the dataset suite (`octax_gym.datasets.suite`) play exactly
the trained network. Needs flax (the `train` extra).

    params = load_params("runs/ppo/agents/Airplane-seed0.msgpack")
    net = describe(params)                    # Network(kind="actor_critic", channels=4, num_actions=17, ...)
    params, net = load_agent("runs/selfplay/agents/Cycles-seed0.msgpack")   # and how it sees its game

An agent file may also hold a `"view"` record beside `"params"`: how the agent sees its game, which
its params alone cannot tell. Today that is `{"mirror": True}` for a self-play agent trained with
`--mirror` (seat 1 sees and plays the mirror image), which must be played in a mirrored env
(`make_multi(..., mirror=True)`) to play what it learned; `octax-gym evaluate` reads it. An agent
of the paper's layout (`--network-layout paper`) records `{"layout": "paper", "planes": F}`: its
params show the layout (its first kernel reads the 64 columns) but not how many frames it reads.
    act = sampling_policy(params, seed=0, num_actions=2)   # numpy (B, 4, 32, 64) -> numpy (B,) actions
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, NamedTuple, Optional

import jax
import jax.numpy as jnp
import numpy as np


class Network(NamedTuple):
    """What an agent file holds: its network, input planes and outputs, and how it sees its game."""

    kind: str  # "actor_critic" (PPO, self-play) or "q_network" (PQN)
    channels: int  # input planes: the frames (plus a player plane for self-play agents)
    num_actions: int  # the network's outputs; a game takes its first actions (no-op, then its keys)
    mirror: bool = False  # trained with mirrored seats (--mirror): play it in a mirrored env
    layout: str = "image"  # how its torso reads the frames (networks.LAYOUTS)


VIEW_KEYS = ("mirror", "layout", "planes")  # what an agent file's "view" record may hold
FRAMES = 4  # an env's frames per step by default: the planes of a paper-layout agent whose file does not say


def load_params(path) -> dict:
    """The params saved at `path` by `octax-gym train` (or the older examples), as float32 JAX arrays.

    Raises:
        ImportError: flax is missing. ValueError: not params of the package's networks.
    """
    return load_agent(path)[0]


def load_agent(path) -> tuple[dict, Network]:
    """(params, network) of the agent file at `path`: `load_params`' params, and `describe`'s
    network with the file's view record (`mirror`, `layout`, `planes`) read.

    Raises:
        ImportError: flax is missing. ValueError: not params of the package's networks, or a view
            record this version does not know.
    """
    path = Path(path)
    try:
        import flax.serialization
    except ImportError as exc:
        raise ImportError(f"{path.name} (JAX params) needs flax: pip install 'octax-gym[train]' ({exc})") from exc
    try:
        saved = flax.serialization.msgpack_restore(path.read_bytes())
        view = dict(saved.pop("view", {}))
        network = describe(saved, view.get("planes"))
    except Exception as exc:  # msgpack's and KeyError's: not a params file of ours
        raise ValueError(f"{path} is not params saved by octax-gym train (flax msgpack of ActorCritic or "
                         f"QNetwork): {exc!r}") from None
    unknown = sorted(set(view) - set(VIEW_KEYS))
    if unknown:
        raise ValueError(f"{path}: its view record holds {unknown}, which this version does not know "
                         f"(it knows {list(VIEW_KEYS)}); a newer octax-gym saved it")
    if view.get("layout", network.layout) != network.layout:
        raise ValueError(f"{path}: its view record says layout {view['layout']!r}, its params are of layout "
                         f"{network.layout!r}: the file was altered")
    params = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32) if np.asarray(x).dtype == np.float16 else jnp.asarray(x),
                          saved)
    return params, network._replace(mirror=bool(view.get("mirror", False)))


def describe(params, planes: Optional[int] = None) -> Network:
    """The kind, input planes, outputs and layout of saved params (read from their shapes; a
    paper-layout network's planes, which its shapes do not show, are `planes`, else FRAMES)."""
    from octax_gym.train.networks import QNetwork, network_for

    network = network_for(params)
    if network.layout == "image":
        channels = int(params["params"]["ConvTorso_0"]["Conv_0"]["kernel"].shape[2])
    else:
        channels = int(planes) if planes is not None else FRAMES
    return Network("q_network" if isinstance(network, QNetwork) else "actor_critic", channels, network.num_actions,
                   layout=network.layout)


def action_scores(params, obs: jax.Array, num_actions: Optional[int] = None) -> jax.Array:
    """The policy's logits (ActorCritic) or Q-values (QNetwork), (B, outputs), of uint8 (B, C, 32, 64);
    with `num_actions`, the actions past a game's own are masked (`networks.masked`)."""
    from octax_gym.train.networks import legal_actions, masked, network_for, scores_of

    scores = scores_of(network_for(params), params, obs)
    if num_actions is None or num_actions == scores.shape[-1]:
        return scores
    return masked(scores, legal_actions(num_actions)[:scores.shape[-1]])


def network_player(greedy: bool, planes: Optional[int] = None):
    """A network as a player of `octax_core.env.players`' signature (one game, one seat; the
    params are the player's argument, so one compiled match serves every checkpoint): its
    scores (`action_scores`) masked to the seat's legal actions, then the largest (greedy) or a
    sample. `planes`: feed the network the observation's first `planes` planes only (a
    one-player agent, frames alone, in a two-player seat, whose observation adds the player
    plane). The self-play trainer's evaluation and `octax-gym evaluate` both play this one."""
    from octax_gym.train.networks import masked

    def act(params, key, obs, state, seat, legal):
        scores = action_scores(params, obs[None] if planes is None else obs[None, :planes])[0]
        scores = masked(scores, jnp.pad(legal, (0, scores.shape[-1] - legal.shape[0])))
        return jnp.argmax(scores) if greedy else jax.random.categorical(key, scores)
    return act


def sampling_policy(params, seed: int, num_actions: Optional[int] = None,
                    epsilon: Optional[float] = None) -> Callable[[np.ndarray], np.ndarray]:
    """A batched policy for `collect_dataset`: the policy the trainer's sampled evaluation plays,
    over the game's `num_actions` actions, from a key chain of `seed` (call i folds i into it):
    the same seed, the same actions.

    An actor-critic (PPO, self-play) samples from the softmax of its logits, the stochastic
    policy PPO trains and is evaluated with. A Q-network (PQN, CQL) plays epsilon-greedy at
    `epsilon` (None: `TrainConfig.eval_epsilon`, 0.005, the paper code's evaluation): the
    softmax of Q-values, which lie close together, would be near-uniform play, not the agent's.
    """
    from octax_gym.train.config import TrainConfig
    from octax_gym.train.networks import legal_actions
    from octax_gym.train.pqn import epsilon_greedy

    key = jax.random.key(seed)
    if describe(params).kind == "q_network":
        epsilon = TrainConfig.eval_epsilon if epsilon is None else float(epsilon)
        if not 0.0 <= epsilon <= 1.0:
            raise ValueError(f"epsilon={epsilon}: a probability, from 0 (greedy) to 1 (uniform random)")

        def choose(params, key, obs):
            q_values = action_scores(params, obs)
            count = q_values.shape[-1] if num_actions is None else num_actions
            return epsilon_greedy(q_values, key, epsilon, legal_actions(count)[:q_values.shape[-1]])
    elif epsilon is not None:
        raise ValueError(f"epsilon={epsilon}: an actor-critic's actions are sampled from its softmax; "
                         "epsilon is for a Q-network's (PQN, CQL) agent")
    else:
        def choose(params, key, obs):
            return jax.random.categorical(key, action_scores(params, obs, num_actions)).astype(jnp.int32)
    draw = jax.jit(choose)
    calls = iter(range(2 ** 31))

    def act(obs: np.ndarray) -> np.ndarray:
        return np.asarray(draw(params, jax.random.fold_in(key, next(calls)), jnp.asarray(obs)))

    act.__name__ = "agent_policy"
    return act
