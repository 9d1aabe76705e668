"""The "archive" suite: games of the Chip8 Community Archive (https://github.com/JohnEarnest/chip8Archive).

Every program there is CC0, so its ROM ships in the package (`octax_core/env/roms/archive/`,
with programs.json, authors.json and a LICENSE.md crediting each author) and these games work
from a plain `pip install`, with no ROM download. A module here holds one game (or one game's
levels): its `SPECS` come from `_program.archive_spec`, which takes the program's platform,
quirks, tickrate and palette from programs.json, and the module adds what the archive does not
say: the keys, the start-up past the title screen, the score, the lives and the end, read from the
program's Octo source (`src/<name>/` in the archive) and checked with `octax-gym trace`.

Ids are the program's title in CamelCase. Where that is already a game's id (the octax suite's
Flight Runner, Spacejam and Tank, our own Dodge), "Archive" is appended: `FlightRunnerArchive`.
Programs that are not games an agent can play and score (title cards, paint programs, music,
visual novels, cellular automata) are left out; `docs/gallery.md` lists every game with its
preview, keys, authors, reward and measured random-play returns and speed.
"""

SUITE = "archive"
