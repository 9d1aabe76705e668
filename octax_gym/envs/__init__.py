"""The envs users make, and what names and registers them: the Gymnasium and PettingZoo faces of
the core's games. Importing this package imports none of its modules (nothing heavy on import).

    env.py           OctaxEnv: one env, a batch of one (gymnasium.make)
    vector.py        OctaxVectorEnv: a real gymnasium.vector.VectorEnv, one jitted call per step
    multi_vector.py  MultiAgentVectorEnv: both seats of a two-player game, batched
    pettingzoo.py    PettingZoo's ParallelEnv and AECEnv over the multi-agent env (public as octax_gym.pettingzoo)
    registration.py  the Gymnasium ids octax/<Game>-v<N>, octax/Mix-v0 (public as octax_gym.registration)
    game_names.py    the one game-name resolver: "pong", "octax/Pong-v0" or a GameSpec, in any case
    choices.py       the one error for an unknown option, naming the valid choices
    render.py        palettes and the OpenCV upscaling of frames
"""
