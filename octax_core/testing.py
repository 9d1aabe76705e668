"""`octax_core.testing.check_env`: the env contract suite, at the short path users reach for.

The suite lives with the env API it checks (`octax_core.env.testing`); this module is its public
address, as `gymnasium.utils.env_checker` is Gymnasium's:

    from octax_core.testing import check_env
    check_env("SuperPong")
"""

from octax_core.env.testing import check_env

__all__ = ["check_env"]
