"""Writes docs/gallery/generated.png, docs/generate.md's strip of generated games:
`python docs/generate_gallery.py ARCHIVE_DIR [ARCHIVE_DIR ...]`.

Takes the first accepted games of each archive (as many from each as fit `--games` in all,
round-robin), plays them side by side in one mix (`octax_gym.generated.load_archive`) with
uniform-random keys from seed 0, and tiles each game's screen after `--steps` steps (or its
screen the step before its first episode ended, where that was sooner) in two rows, 4x upscaled, in the "white" palette.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

OUT = Path(__file__).resolve().parent / "gallery" / "generated.png"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("archives", nargs="+", type=Path, help="folders `octax-gym generate` wrote")
    parser.add_argument("--games", type=int, default=8, help="games in the strip (default 8)")
    parser.add_argument("--steps", type=int, default=40, help="random-play steps before the picture (default 40)")
    parser.add_argument("--out", type=Path, default=OUT, help=f"the image (default {OUT})")
    args = parser.parse_args(argv)
    import cv2
    import jax
    import jax.numpy as jnp

    import octax_core
    from octax_core.emulator.state import screen_pixels
    from octax_gym.envs import render
    from octax_gym.generated import load_archive

    per_archive = [load_archive(folder) for folder in args.archives]
    specs = []
    while len(specs) < args.games and any(per_archive):
        for games in per_archive:
            if games and len(specs) < args.games:
                specs.append(games.pop(0))
    env, params = octax_core.make_mix(specs)
    n = len(specs)
    _, states = jax.vmap(lambda k, g: env.reset(k, params, game=g))(jax.random.split(jax.random.key(0), n),
                                                                      jnp.arange(n))

    @jax.jit
    def step(states, key):
        keys = jax.random.split(key, 2 * n)
        actions = jax.vmap(lambda k: jax.random.randint(k, (), 0, env.num_actions))(keys[:n])
        return jax.vmap(env.step_env, in_axes=(0, 0, 0, None))(keys[n:], states, actions, params)[1]
    shown = states.machine  # each game's last screen while its first episode was on
    for t in range(args.steps):
        states = step(states, jax.random.fold_in(jax.random.key(1), t))
        shown = jax.tree.map(lambda new, old: jnp.where(
            jnp.reshape(states.done, (-1,) + (1,) * (old.ndim - 1)), old, new), states.machine, shown)
    palette = render.resolve_palette("white")
    frames = [render.to_rgb(screen_pixels(jax.tree.map(lambda x: x[i], shown)), 4, palette)
              for i in range(n)]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out), cv2.cvtColor(render.tile(frames, columns=(n + 1) // 2, gap=4), cv2.COLOR_RGB2BGR))
    print(f"wrote {args.out}: " + ", ".join(spec.id for spec in specs))
    return 0


if __name__ == "__main__":
    sys.exit(main())
