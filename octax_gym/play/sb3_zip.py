"""A Stable-Baselines3 zip read as data: its policy rebuilt without unpickling anything from the file.

SB3's own `PPO.load` unpickles (cloudpickle) the spaces, the policy class and the policy kwargs
stored in the zip's `data` entry, so a zip can run any code it likes the moment it is loaded. A
file handed to `octax-gym play --agent` may come from anyone, so here:

* `data` is parsed as JSON and only its plain fields are read: next to each pickle
  (`":serialized:"`, never decoded) SB3 writes the object's readable fields, e.g. the policy
  class's `__module__` and the kwargs' `activation_fn` as the text "<class '...ReLU'>";
* `policy.pth` is read by `torch.load(weights_only=True)`, which builds tensors and plain
  containers only;
* the policy is rebuilt from the architectures this project trains (SB3's actor-critic policy of
  PPO and A2C, or DQN's Q-network, over `octax_gym.integrations.sb3.OctaxCNNExtractor`), the layer sizes taken
  from the weights' shapes, and the weights loaded strictly (every name and shape must match).

Anything else cannot be rebuilt without running code from the file and is refused with an
`AgentFileError`; `octax-gym play --trust-agent` hands such a file to SB3's own loader instead.
"""

from __future__ import annotations

import io
import json
import re
import zipfile
from pathlib import Path
from typing import Any, NamedTuple

import gymnasium
import torch
from stable_baselines3.common.policies import ActorCriticPolicy, BasePolicy
from stable_baselines3.dqn.policies import DQNPolicy

from octax_gym.integrations.sb3 import OctaxCNNExtractor

# The policy classes' modules, as SB3 writes `policy_class.__module__` in `data`: which family.
POLICY_MODULES = {"stable_baselines3.common.policies": "actor-critic (PPO, A2C)",
                  "stable_baselines3.dqn.policies": "DQN"}
EXTRACTOR = f"<class '{OctaxCNNExtractor.__module__}.{OctaxCNNExtractor.__qualname__}'>"
ACTIVATIONS = {f"<class '{cls.__module__}.{cls.__qualname__}'>": cls
               for cls in (torch.nn.ReLU, torch.nn.Tanh, torch.nn.ELU, torch.nn.LeakyReLU, torch.nn.SiLU)}
# policy_kwargs that only train (the optimizer, the initialisation): read by nothing here.
TRAINING_ONLY = {"optimizer_class", "optimizer_kwargs", "ortho_init"}
READ = {"features_extractor_class", "features_extractor_kwargs", "activation_fn", "net_arch",
        "share_features_extractor", "normalize_images"}
MAX_ENTRY_BYTES = 256 * 2 ** 20  # the paper's network is ~2 MB; a bigger entry is not one of ours
MAX_ACTIONS, MAX_UNITS = 256, 4096  # bounds on what the file may ask the player to allocate
TRUST_HINT = ("only if you trust the file and where it came from, --trust-agent loads it with SB3's own loader, "
              "which runs code stored in the file")


class AgentFileError(ValueError):
    """An agent file this player will not load without `--trust-agent`: the message says why."""


class Sb3Policy(NamedTuple):
    """A rebuilt SB3 policy (eval mode, CPU) and what it plays."""

    policy: BasePolicy  # .predict(obs, deterministic=True) as the model's own
    channels: int  # input planes (frames)
    num_actions: int


def load_policy(path) -> Sb3Policy:
    """The policy of the SB3 zip at `path`, rebuilt from its JSON fields and tensors only.

    Raises:
        AgentFileError: not a zip of a policy this module rebuilds (the message names what is
            missing or different, and `--trust-agent`).
    """
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as archive:
            data = _json(_entry(archive, "data"))
            weights = _weights(_entry(archive, "policy.pth"))
        family = _family(data.get("policy_class"))
        kwargs = _policy_kwargs(data.get("policy_kwargs"), family)
        channels = _channels(data.get("observation_space"))
        return _rebuild(family, kwargs, weights, channels, _declared_actions(data.get("action_space")))
    except AgentFileError as exc:
        raise AgentFileError(f"{path} is not a Stable-Baselines3 model this player can load without running code "
                             f"from it: {exc}; {TRUST_HINT}") from None
    except zipfile.BadZipFile as exc:
        raise AgentFileError(f"{path} is not a readable zip ({exc})") from None


def _entry(archive: zipfile.ZipFile, name: str) -> bytes:
    try:
        info = archive.getinfo(name)
    except KeyError:
        raise AgentFileError(f"it has no {name!r} entry (an SB3 model.save() zip has 'data' and "
                             "'policy.pth')") from None
    if info.file_size > MAX_ENTRY_BYTES:
        raise AgentFileError(f"its {name!r} entry is {info.file_size:,} bytes, over {MAX_ENTRY_BYTES:,}")
    return archive.read(info)


def _json(raw: bytes) -> dict:
    try:
        data = json.loads(raw)
    except ValueError as exc:  # UnicodeDecodeError and JSONDecodeError
        raise AgentFileError(f"its 'data' entry is not JSON ({exc})") from None
    except RecursionError:
        raise AgentFileError("its 'data' entry nests too deep to be SB3's JSON") from None
    if not isinstance(data, dict):
        raise AgentFileError(f"its 'data' entry is a JSON {type(data).__name__}, not an object")
    return data


def _weights(raw: bytes) -> dict[str, torch.Tensor]:
    try:
        weights = torch.load(io.BytesIO(raw), map_location="cpu", weights_only=True)
    except Exception as exc:  # weights_only refuses every pickled object but tensors and containers
        raise AgentFileError(f"its 'policy.pth' is not plain tensors ({str(exc).splitlines()[0][:200]})") from None
    if not isinstance(weights, dict) or not all(isinstance(k, str) and isinstance(v, torch.Tensor)
                                                for k, v in weights.items()):
        raise AgentFileError("its 'policy.pth' is not a state dict (names -> tensors)")
    return weights


def _readable(entry: Any, name: str) -> dict:
    """An entry's readable fields: SB3 writes a pickled object as {":type:", ":serialized:", field: value...}."""
    if not isinstance(entry, dict):
        raise AgentFileError(f"its {name!r} is {'missing' if entry is None else type(entry).__name__}")
    return {key: value for key, value in entry.items() if key not in (":type:", ":serialized:")}


def _family(entry: Any) -> str:
    module = _readable(entry, "policy_class").get("__module__")
    if module not in POLICY_MODULES:
        kind = entry.get(":type:", "?") if isinstance(entry, dict) else "?"
        raise AgentFileError(f"its policy_class is {kind} from module {module!r}, not a Stable-Baselines3 policy "
                             f"(one of {sorted(POLICY_MODULES)})")
    return POLICY_MODULES[module]


def _policy_kwargs(entry: Any, family: str) -> dict:
    fields = {} if entry is None else _readable(entry, "policy_kwargs")
    unknown = sorted(set(fields) - READ - TRAINING_ONLY)
    if unknown:
        raise AgentFileError(f"its policy_kwargs set {unknown}; this player rebuilds policies set by "
                             f"{sorted(READ | TRAINING_ONLY)} only")
    extractor = fields.get("features_extractor_class", "SB3's default (NatureCNN or FlattenExtractor)")
    if extractor != EXTRACTOR:
        raise AgentFileError(f"its features extractor is {extractor}; this player rebuilds {EXTRACTOR} only "
                             "(octax_gym.sb3's, the paper's CNN)")
    default_activation = torch.nn.ReLU if family == "DQN" else torch.nn.Tanh
    activation = fields.get("activation_fn")
    if activation is not None and activation not in ACTIVATIONS:
        raise AgentFileError(f"its activation_fn is {activation}; this player knows {sorted(ACTIVATIONS)}")
    flags = {}
    for name in ("share_features_extractor", "normalize_images"):
        flags[name] = fields.get(name, True)
        if not isinstance(flags[name], bool):
            raise AgentFileError(f"its policy_kwargs {name} is {flags[name]!r}, not true or false")
    return {"activation_fn": ACTIVATIONS.get(activation, default_activation), **flags}


def _channels(entry: Any) -> int:
    """The frames of the observation space SB3 saw: uint8 0..255 (frames, 32, 64), octax_gym.integrations.sb3's."""
    fields = _readable(entry, "observation_space")
    shape, dtype = fields.get("_shape"), fields.get("dtype")
    # low and high are written as numpy's summarised text ("[[[0 0 0 ... 0 0 0] ..."): every number shown must match
    bounds = [re.findall(r"-?\d+(?:\.\d*)?(?:e[-+]?\d+)?|inf|nan", str(fields.get(side, "")))
              for side in ("low", "high")]
    if (dtype != "uint8" or not isinstance(shape, list) or len(shape) != 3 or shape[1:] != [32, 64]
            or not isinstance(shape[0], int) or not 1 <= shape[0] < 32
            or set(bounds[0]) != {"0"} or set(bounds[1]) != {"255"}):
        low, high = ("/".join(sorted(set(values))[:4]) or "?" for values in bounds)
        raise AgentFileError(f"it was trained on observations {dtype} {str(shape)[:40]} of values {low}..{high}; this "
                             "player rebuilds agents of octax_gym.sb3's uint8 0..255 (frames, 32, 64) images")
    return shape[0]


def _declared_actions(entry: Any) -> int:
    n = _readable(entry, "action_space").get("n")
    if not (isinstance(n, int) or isinstance(n, str) and n.isdigit() and len(n) < 6) or not 1 <= int(n) <= MAX_ACTIONS:
        raise AgentFileError(f"its action_space is not a Discrete space of 1..{MAX_ACTIONS} actions "
                             f"(n = {str(n)[:20]!r})")
    return int(n)


def _layer_sizes(weights: dict, prefix: str) -> list[int]:
    """Output sizes of the Linear layers `prefix<i>.weight` of an SB3 MLP (Sequential), in order."""
    found = sorted((int(m.group(1)), tensor.shape[0]) for name, tensor in weights.items()
                   if tensor.dim() == 2 and (m := re.fullmatch(re.escape(prefix) + r"(\d{1,3})\.weight", name)))
    sizes = [size for _, size in found]
    if len(sizes) > 16 or any(size > MAX_UNITS for size in sizes):
        raise AgentFileError(f"its layers {prefix}* have {sizes[:20]} units; this player builds at most 16 layers "
                             f"of at most {MAX_UNITS}")
    return sizes


def _rebuild(family: str, kwargs: dict, weights: dict, channels: int, num_actions: int) -> Sb3Policy:
    prefix = "q_net." if family == "DQN" else ""
    head = weights.get(f"{prefix}features_extractor.head.0.weight")
    head_dim = None if head is None or head.dim() != 2 else int(head.shape[0])
    if head_dim is not None and not 1 <= head_dim <= MAX_UNITS:
        raise AgentFileError(f"its features extractor's head has {head_dim} units; at most {MAX_UNITS}")
    extractor_kwargs = {"head_dim": head_dim}
    observation_space = gymnasium.spaces.Box(0, 255, (channels, 32, 64), "uint8")
    action_space = gymnasium.spaces.Discrete(num_actions)
    common = dict(lr_schedule=lambda _: 0.0, activation_fn=kwargs["activation_fn"],
                  features_extractor_class=OctaxCNNExtractor, features_extractor_kwargs=extractor_kwargs,
                  normalize_images=kwargs["normalize_images"])
    if family == "DQN":
        policy = DQNPolicy(observation_space, action_space, net_arch=_layer_sizes(weights, "q_net.q_net.")[:-1],
                           **common)
    else:
        net_arch = {"pi": _layer_sizes(weights, "mlp_extractor.policy_net."),
                    "vf": _layer_sizes(weights, "mlp_extractor.value_net.")}
        policy = ActorCriticPolicy(observation_space, action_space, net_arch=net_arch,
                                   share_features_extractor=kwargs["share_features_extractor"], **common)
    try:
        policy.load_state_dict(weights, strict=True)
    except RuntimeError as exc:  # names or shapes that are not this network's
        raise AgentFileError(f"its weights do not fit the {family} policy over OctaxCNNExtractor for {channels} "
                             f"frames and {num_actions} actions ({' '.join(str(exc).split())[:300]})") from None
    policy.set_training_mode(False)
    return Sb3Policy(policy, channels, num_actions)
