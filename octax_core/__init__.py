"""octax_core: CHIP-8 games as jitted, batched RL environments in pure JAX + numpy.

Three layers, each a subpackage that imports only the ones before it:

* `octax_core.emulator`: the CHIP-8, SUPER-CHIP and XO-CHIP machines (state pytree, decode, ops,
  cpu, `Machine`);
* `octax_core.env`: the game registry, the ROM store and the functional, Gymnax-style env API;
* `octax_core.tools`: the Octo assembler and disassembler, and the register tracer.

The names below are the public API. See docs/machine.md (the machine) and docs/env.md (the envs).
``OCTAX_CPU_THREADS`` (read here, before anything else starts JAX) sizes XLA:CPU's thread pool;
see `octax_core.host`. Importing octax_core also lowers JAX's Threefry hash unrolled on CPU, the
same bits in fewer kernels, for every program of the process (``OCTAX_ROLLED_THREEFRY=1`` keeps
JAX's loop); see `octax_core.threefry`.

`__version__` is the installed distribution's (`octax-gym`, whose version pyproject.toml sets):
read from the package metadata rather than written here too, so there is one number to bump;
`octax_gym.__version__` and `octax-gym --version` are this one.
"""

from importlib import metadata as _metadata

from octax_core import host, threefry

try:
    __version__ = _metadata.version("octax-gym")
except _metadata.PackageNotFoundError:  # a source tree on sys.path, never installed: no metadata to read
    __version__ = "0+unknown"

host.apply_environment()  # before any import below can start JAX's backends
threefry.apply_environment()  # before any program is lowered: Threefry unrolled on CPU


from octax_core.emulator import (FONT, FONT_ADDRESS, MAX_ROM_SIZE, PLATFORMS, PROGRAM_ADDRESS, QUIRK_PROFILES, Kind,
                                 Machine, MachineState, Platform, Quirks, Rom, poke, render_text, snapshot)
from octax_core.env import (Env, EnvConfig, EnvParams, EnvState, GameSpec, MixEnv, MultiEnv, Seats, get_spec, list_games,
                            make, make_config, make_mix, make_multi, make_params)
from octax_core.env.games import UnknownGameError
from octax_core.env.testing import check_env
from octax_core.host import limit_cpu_threads
from octax_core.tools.octo import AssemblyError, assemble

__all__ = [
    "AssemblyError", "FONT", "FONT_ADDRESS", "Env", "EnvConfig", "EnvParams", "EnvState", "GameSpec", "Kind",
    "MAX_ROM_SIZE", "Machine", "MachineState", "MixEnv", "MultiEnv", "Seats", "PLATFORMS", "PROGRAM_ADDRESS", "Platform", "QUIRK_PROFILES",
    "Quirks", "Rom", "UnknownGameError", "__version__",
    "assemble", "check_env", "disassemble", "get_spec", "limit_cpu_threads", "list_games", "make", "make_config", "make_mix", "make_multi", "make_params", "poke",
    "render_text", "snapshot",
]


def __getattr__(name):
    # The disassembler loads on first use (`octax_core.disassemble`), like optional extras do.
    if name == "disassemble":
        from octax_core.tools.octo.disassembler import disassemble
        return disassemble
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
