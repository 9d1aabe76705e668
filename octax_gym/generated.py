"""Generated games as envs: an archive written by `octax-gym generate`, read back as GameSpecs.

    specs = load_archive("generated/dodger", split="train")
    env, params = octax_core.make_mix(specs)                                # one batch, every variant
    envs = gymnasium.make_vec("octax/Mix-v0", num_envs=64, games=specs)    # the same, in Gymnasium

Each spec names its ROM by the archive's own file (an absolute path, which the ROM store's
lookup takes as it is) and its hash, so the archive's folder needs no installing. The variants
of a family share their score, lives and end functions (`octax_core.generate.build`): in a mix
they differ only in the ROM each env's machine holds.

Splits are by family parameters (`Family.split`, `Family.held_out`: as Procgen and Kinetix hold
out levels, a range of one parameter is held out): "train", "test", or None for both.
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from octax_core.env.games.spec import GameSpec
from octax_core.generate import archive
from octax_core.generate.build import variant_spec


def load_archive(folder, split: Optional[str] = None, *, accepted_only: bool = True) -> list[GameSpec]:
    """The archive's games as GameSpecs, in archive order.

    Args:
        folder: the folder `octax-gym generate --out` wrote.
        split: "train", "test", or None (both).
        accepted_only: leave out the games the filters rejected (the default); False keeps every
            game that assembled.

    Raises:
        ValueError: no archive there, an unknown split, or no game left to load (the message
            counts what the archive holds).
    """
    if split is not None and split not in archive.SPLITS:
        raise ValueError(f"unknown split {split!r}; valid: {', '.join(archive.SPLITS)} or None (both)")
    folder = Path(folder).expanduser().resolve()
    games = archive.read(folder)["games"]
    chosen = [game for game in games if game["rom"] is not None and (game["accepted"] or not accepted_only)
              and (split is None or game["split"] == split)]
    if not chosen:
        accepted = sum(game["accepted"] for game in games)
        raise ValueError(f"{folder}: no {'accepted ' if accepted_only else ''}game in split {split or 'train+test'} "
                         f"(the archive holds {len(games)} games, {accepted} accepted: "
                         + ", ".join(f"{s} {sum(g['split'] == s and g['accepted'] for g in games)}" for s in archive.SPLITS)
                         + ")")
    return [variant_spec(game["name"], game["sha1"], game["action_keys"], rom_file=str(folder / game["rom"]),
                         registers=game["registers"],
                         description=f"generated: family {game['family']}, params {game['params']}")
            for game in chosen]
