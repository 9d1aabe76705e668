"""Prints the games table of docs/games.md from the registry: `python docs/games_table.py`.

The octax paper's suite and our own games; the archive suite has its own page, docs/gallery.md
(`python docs/gallery.py`), with previews and measured play.

tests/core_games/test_all_games.py checks that docs/games.md holds exactly this output.
"""

import octax_core

HEADER = ("| id | category | actions (keys) | quirks | timers | max steps | ROM |\n"
          "|---|---|---|---|---|---|---|")


def games_table() -> str:
    rows = [HEADER]
    for game_id in sorted(octax_core.list_games("octax") + octax_core.list_games("ours")):
        spec = octax_core.get_spec(game_id)
        keys = ", ".join(f"{k:X}" for k in spec.action_keys)
        timers = "frozen" if spec.freeze_timers else "60 Hz"
        rows.append(f"| {spec.id} | {spec.category} | {len(spec.action_keys) + 1} ({keys}) | "
                    f"{spec.quirks} | {timers} | {spec.max_episode_steps} | `{spec.rom_file}` |")
    return "\n".join(rows)


if __name__ == "__main__":
    print(games_table())
