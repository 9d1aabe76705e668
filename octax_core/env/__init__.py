"""The env API: CHIP-8, SUPER-CHIP and XO-CHIP games as functional, batched RL environments
(Gymnax-style).

`games/` is the registry (one `GameSpec` per game), `romstore` finds and verifies each game's
ROM, `config` declares the options, `starts` makes the start states (start-up and no-op starts)
once per env, `environment` is the env (`make`, `Env.reset`/`step`/`autoreset`), `multi` the two-player env
on top of it (`make_multi`), `mix` many games in one batch (`make_mix`), and `testing` the contract suite
every game passes. Built on `octax_core.emulator`; nothing here imports Gymnasium or torch.
See docs/env.md.
"""

from octax_core.env.config import ENV_OPTIONS, EnvConfig, EnvParams, make_config, make_params
from octax_core.env.environment import Env, EnvState, make
from octax_core.env.games import SUITES, GameSpec, Seats, get_spec, list_games, suite_of
from octax_core.env.mix import MixEnv, make_mix
from octax_core.env.multi import MultiEnv, make_multi

__all__ = ["ENV_OPTIONS", "Env", "EnvConfig", "EnvParams", "EnvState", "GameSpec", "MixEnv", "MultiEnv", "SUITES", "Seats", "get_spec",
           "list_games", "make", "make_config", "make_mix", "make_multi", "make_params", "suite_of"]
