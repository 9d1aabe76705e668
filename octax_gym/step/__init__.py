"""What runs a step behind the envs: the compiled step and what it needs to check actions, play a
fixed opponent, put arrays on a backend and spread a batch over devices and processes. Importing
this package imports none of its modules (nothing heavy on import).

    compiled_step.py  the compiled env step: key chains, autoreset modes, info masks over the core step
    action_check.py   every action check and conversion, host and device actions alike
    opponent.py       one seat of a two-player game against a fixed opponent (public as octax_gym.opponent)
    backends.py       numpy, JAX or torch outputs, and the devices they live on
    sharding.py       a batch sharded over devices (devices=)
    distributed.py    joining a multi-process run: jax.distributed, Gloo on CPU (public as octax_gym.distributed)
    handshake.py      the processes' rendezvous before jax.distributed starts
"""
