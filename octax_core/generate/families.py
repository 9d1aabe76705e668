"""The procedural families: Octo templates with parameters, and the ranges each parameter takes.

A family is one game written once, with its speeds, sizes, counts and sprite shapes left as
parameters; a variant is the template with every parameter filled in, a different program.
Every template keeps the same register map as our own games (roms/*.8o): the score in V5, the
lives in V6, VE = 1 once the game is over, so that one GameSpec score and end function serves
every variant of every family (`octax_core.generate.build`): the ROM is data.

Templates use `string.Template`'s `$name` (Octo uses no `$`). Sprite shapes are parameters too:
a tuple of row bytes, drawn from a seed by `octax_core.generate.sample`.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

SCORE, LIVES, GAME_OVER = 5, 6, 14  # V5, V6, VE: the registers every family keeps them in


@dataclasses.dataclass(frozen=True)
class Family:
    """One family of games.

    Attributes:
        name: the family's name ("dodger"), used in variant names and on the command line.
        description: one line: the game, its keys, its reward and its end.
        action_keys: the CHIP-8 keys actions 1..k hold (the same for every variant).
        ranges: each integer parameter's (low, high), both included.
        sprites: each sprite parameter's (width range, height range): a shape of that many rows
            of that many pixels, drawn from the seed.
        split: the parameter whose values `held_out` are the test split (as Procgen and Kinetix
            hold out levels): a variant with params[split] in held_out is "test", else "train".
        held_out: the split parameter's held-out values.
        derive: params -> the template's other fields (positions, bounds) computed from them.
        template: the Octo source with `$name` fields.
    """

    name: str
    description: str
    action_keys: tuple[int, ...]
    ranges: Mapping[str, tuple[int, int]]
    sprites: Mapping[str, tuple[tuple[int, int], tuple[int, int]]]
    split: str
    held_out: tuple[int, ...]
    derive: Callable[[dict], dict]
    template: str

    def split_of(self, params: Mapping) -> str:
        """"test" where the variant's split parameter is in the held-out range, else "train"."""
        return "test" if params[self.split] in self.held_out else "train"


# --- the fallers: things fall down the screen onto a ship on the bottom rows -----------------
# One template serves the dodger (a thing landing beside the ship scores, on it costs a life)
# and the catcher (the reverse): `near` and `far` name the routine each case jumps to.

# The score (three digits, top left), the lives (top right) and the end screen: the same routines in
# every family, so every variant shows its score and end the same way.
_SCOREBOARD = r""": draw-score
	i := bcd-buffer
	bcd score
	load v2
	draw-x := 0
	draw-y := 0
	i := hex v0
	sprite draw-x draw-y 5
	draw-x += 5
	i := hex v1
	sprite draw-x draw-y 5
	draw-x += 5
	i := hex digit
	sprite draw-x draw-y 5
return

: draw-lives
	draw-x := 59
	draw-y := 0
	i := hex lives
	sprite draw-x draw-y 5
return

: game-over
	clear
	draw-x := 24
	draw-y := 13
	i := bcd-buffer
	bcd score
	load v2
	i := hex v0
	sprite draw-x draw-y 5
	draw-x += 6
	i := hex v1
	sprite draw-x draw-y 5
	draw-x += 6
	i := hex digit
	sprite draw-x draw-y 5
	loop again
"""

_FALLERS = r"""
###############################################################################
# $title: a procedurally generated variant (octax_core.generate, family $family).
# Key 4 moves the ship left, key 6 right ($step pixels a move).
# Registers the environment reads: v5 score, v6 lives, vE game over (1).
###############################################################################

:alias obj-x  v0
:alias obj-y  v1
:alias digit  v2
:alias ship-x v3
:alias score  v5
:alias lives  v6
:alias obj    v7
:alias tmp    vA
:alias draw-x vB
:alias draw-y vC
:alias over   vE

: main
	start
	loop
		obj := 0
		loop
			move-ship
			move-obj
			if over == 1 then jump game-over
			obj += 2
			while obj != $objs_end
		again
	again

: start
	tmp := 24
	delay := tmp
	score := 0
	lives := $lives
	over := 0
	ship-x := $ship_start
	clear
	draw-line
	draw-score
	draw-lives
	draw-ship
	loop
		tmp := delay
		while tmp != 0
	again
	draw-y := 7
	obj := 0
	loop
		random-column
		obj-y := draw-y
		i := obj-sprite
		sprite obj-x obj-y $thing_h
		i := objs
		i += obj
		save v1
		draw-y += $spacing
		obj += 2
		while obj != $objs_end
	again
return

: draw-line
	i := line
	draw-x := 0
	draw-y := 5
	loop
		sprite draw-x draw-y 1
		draw-x += 8
		while draw-x != 64
	again
return

: move-ship
	tmp := 4
	if tmp key begin
		if ship-x != 0 begin
			draw-ship
			ship-x -= $step
			draw-ship
		end
	end
	tmp := 6
	if tmp key begin
		if ship-x != $ship_max begin
			draw-ship
			ship-x += $step
			draw-ship
		end
	end
return

: draw-ship
	i := ship
	tmp := $ship_y
	sprite ship-x tmp $ship_h
return

: move-obj
	i := objs
	i += obj
	load v1
	i := obj-sprite
	sprite obj-x obj-y $thing_h
	obj-y += $fall
	if obj-y >= $ground then jump land
	sprite obj-x obj-y $thing_h
	jump store-obj

# The thing covers obj-x..obj-x+$thing_w-1 and the ship ship-x..ship-x+$ship_w-1: they
# overlap when obj-x + $thing_w - 1 - ship-x is 0..$reach_last (below 0 wraps past 190).
: land
	tmp := obj-x
	tmp += $thing_last
	tmp -= ship-x
	if tmp < $reach then jump $near
	jump $far
: point
	draw-score
	score += 1
	draw-score
	if score == $win then over := 1
	jump respawn
: hit
	draw-lives
	lives -= 1
	draw-lives
	tmp := 6
	buzzer := tmp
	if lives == 0 then over := 1
: respawn
	random-column
	obj-y := 7
	i := obj-sprite
	sprite obj-x obj-y $thing_h
: store-obj
	i := objs
	i += obj
	save v1
return

: random-column
	obj-x := random 63
	if obj-x > $x_max then obj-x -= 32
return

""" + _SCOREBOARD + r"""
: ship
	$ship
: obj-sprite
	$thing
: line
	0b11111111
: bcd-buffer
	0 0 0
: objs
	0 0 0 0 0 0 0 0
"""


def _fallers_fields(near: str, far: str, title: str, family: str):
    def derive(p: dict) -> dict:
        ship_y = 32 - p["ship_h"]
        ground = ship_y - p["thing_h"] + 1
        ship_max = (64 - p["ship_w"]) // p["step"] * p["step"]
        return dict(title=title, family=family, near=near, far=far, objs_end=2 * p["things"],
                    ship_y=ship_y, ground=ground, ship_max=ship_max,
                    ship_start=ship_max // 2 // p["step"] * p["step"],
                    spacing=max(1, (ground - 7) // p["things"]), thing_last=p["thing_w"] - 1,
                    reach=p["thing_w"] + p["ship_w"] - 1, reach_last=p["thing_w"] + p["ship_w"] - 2,
                    x_max=64 - p["thing_w"], win=200)
    return derive


_FALLER_RANGES = {"things": (1, 4), "fall": (1, 3), "step": (1, 3), "lives": (1, 5)}

DODGER = Family(
    name="dodger",
    description="Things fall; move the ship (keys 4 left, 6 right) to let them land beside it: +1 each; "
                "one landing on it costs a life; the game ends with the last life or at 200.",
    action_keys=(4, 6), ranges=_FALLER_RANGES,
    sprites={"ship": ((4, 8), (2, 4)), "thing": ((2, 6), (2, 5))},
    split="fall", held_out=(3,),
    derive=_fallers_fields("hit", "point", "Dodger", "dodger"), template=_FALLERS)

CATCHER = Family(
    name="catcher",
    description="Things fall; move the basket (keys 4 left, 6 right) under them: +1 for each caught; "
                "one that lands beside it costs a life; the game ends with the last life or at 200.",
    # fewer things and a faster, wider basket than the dodger's ship: catching every thing of
    # four, scattered over 64 columns, is out of any player's reach
    action_keys=(4, 6), ranges={"things": (1, 2), "fall": (1, 3), "step": (2, 4), "lives": (1, 5)},
    sprites={"ship": ((6, 8), (2, 4)), "thing": ((2, 6), (2, 5))},
    split="fall", held_out=(3,),
    derive=_fallers_fields("point", "hit", "Catcher", "catcher"), template=_FALLERS)

# --- the paddle game: a ball bounces off three walls; the paddle at the bottom returns it ----

_PADDLE = r"""
###############################################################################
# Paddle: a procedurally generated variant (octax_core.generate, family paddle).
# Key 4 moves the paddle left, key 6 right ($step pixels a move); +1 for each return.
# Registers the environment reads: v5 score, v6 lives, vE game over (1).
###############################################################################

:alias ball-x v0
:alias ball-y v1
:alias digit  v2
:alias pad-x  v3
:alias score  v5
:alias lives  v6
:alias dx     v8
:alias dy     v9
:alias tmp    vA
:alias draw-x vB
:alias draw-y vC
:alias over   vE

: main
	start
	loop
		move-paddle
		move-ball
		if over == 1 then jump game-over
	again

: start
	tmp := 24
	delay := tmp
	score := 0
	lives := $lives
	over := 0
	pad-x := $pad_start
	clear
	draw-line
	draw-score
	draw-lives
	draw-paddle
	loop
		tmp := delay
		while tmp != 0
	again
	serve
return

: serve
	ball-x := random $serve_mask
	ball-x += $serve_min
	ball-y := 7
	dy := $speed_y
	dx := $speed_x
	tmp := random 1
	if tmp == 0 then dx := $speed_x_back
	i := ball
	sprite ball-x ball-y $ball_h
return

: draw-line
	i := line
	draw-x := 0
	draw-y := 5
	loop
		sprite draw-x draw-y 1
		draw-x += 8
		while draw-x != 64
	again
return

: move-paddle
	tmp := 4
	if tmp key begin
		if pad-x != 0 begin
			draw-paddle
			pad-x -= $step
			draw-paddle
		end
	end
	tmp := 6
	if tmp key begin
		if pad-x != $pad_max begin
			draw-paddle
			pad-x += $step
			draw-paddle
		end
	end
return

: draw-paddle
	i := paddle
	tmp := $pad_y
	sprite pad-x tmp $paddle_h
return

# Walls: the ball turns where its next move would leave the field (left, right, top).
: move-ball
	i := ball
	sprite ball-x ball-y $ball_h
	if dx == $speed_x begin
		tmp := ball-x
		tmp += $speed_x
		if tmp > $ball_x_max then dx := $speed_x_back
	else
		if ball-x < $speed_x then dx := $speed_x
	end
	ball-x += dx
	if dy != $speed_y begin
		tmp := ball-y
		tmp -= 7
		if tmp < $speed_y then dy := $speed_y
	end
	ball-y += dy
	if ball-y >= $ball_y_max then jump bottom
	sprite ball-x ball-y $ball_h
return

# The ball is down at the paddle's rows: ball-x..ball-x+$ball_last and pad-x..pad-x+$pad_last
# overlap when ball-x + $ball_last - pad-x is 0..$reach_last (below 0 wraps past 190).
: bottom
	ball-y := $ball_y_max
	tmp := ball-x
	tmp += $ball_last
	tmp -= pad-x
	if tmp < $reach then jump return-ball
	draw-lives
	lives -= 1
	draw-lives
	tmp := 6
	buzzer := tmp
	if lives == 0 then over := 1
	jump serve
: return-ball
	dy := $speed_y_back
	draw-score
	score += 1
	draw-score
	if score == 200 then over := 1
	i := ball
	sprite ball-x ball-y $ball_h
return

""" + _SCOREBOARD + r"""
: paddle
	$paddle
: ball
	$ball
: line
	0b11111111
: bcd-buffer
	0 0 0
"""


def _paddle_fields(p: dict) -> dict:
    pad_y = 32 - p["paddle_h"]
    pad_max = (64 - p["paddle_w"]) // p["step"] * p["step"]
    ball_x_max = pad_max + p["paddle_w"] - p["ball_w"]  # the right wall: where the paddle's right edge reaches
    return dict(pad_y=pad_y, pad_max=pad_max, pad_start=pad_max // 2 // p["step"] * p["step"],
                ball_y_max=pad_y - p["ball_h"], ball_x_max=ball_x_max, ball_last=p["ball_w"] - 1,
                pad_last=p["paddle_w"] - 1, reach=p["ball_w"] + p["paddle_w"] - 1,
                reach_last=p["ball_w"] + p["paddle_w"] - 2,
                speed_x_back=256 - p["speed_x"], speed_y_back=256 - p["speed_y"],
                serve_mask=31, serve_min=(ball_x_max - 31) // 2)


PADDLE = Family(
    name="paddle",
    description="A ball bounces off the walls; move the paddle (keys 4 left, 6 right) under it: +1 for "
                "each return; a miss costs a life; the game ends with the last life or at 200.",
    # the paddle moves at least as fast as the ball across (step 3 or 4 against 1..3 a move), so
    # that every ball can be reached: a miss is the player's, never the parameters'
    action_keys=(4, 6), ranges={"speed_x": (1, 3), "speed_y": (1, 2), "step": (3, 4), "lives": (1, 5)},
    sprites={"paddle": ((6, 8), (1, 2)), "ball": ((1, 3), (1, 3))},
    split="speed_x", held_out=(3,), derive=_paddle_fields, template=_PADDLE)

FAMILIES: dict[str, Family] = {family.name: family for family in (DODGER, CATCHER, PADDLE)}


def get_family(name: str) -> Family:
    """The family called `name`; a KeyError that lists the families for any other."""
    if name not in FAMILIES:
        raise KeyError(f"unknown family {name!r}; valid: {', '.join(FAMILIES)}")
    return FAMILIES[name]
