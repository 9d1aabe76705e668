"""`octax-gym evaluate` (octax_gym/cli/evaluate.py): a player name against the ladder of a real game,
and a small saved network (the trainer's ActorCritic, saved as the loop saves agents) on
tests/two_player_games.py's TwoCounters, where the key a network holds decides every game
(its first key scores 4 a step, its second 8, as the scripted player does; 24 wins).

Each evaluation compiles a match per (game, mirrored or not, greedy or sampled, episodes, steps):
the network tests play TwoCounters with 4 episodes of 10 steps in two of them, the plain env
greedy and the mirrored env sampled (where a preferred key's logit leaves sampling no choice)."""

from __future__ import annotations

import dataclasses
import json

import jax
import jax.numpy as jnp
import pytest

from octax_core.env.ladder import RUNGS
from octax_gym import cli
from octax_gym.cli.evaluate import evaluate, format_result

from two_player_games import TWO_COUNTERS

pytest.importorskip("flax")

# TwoCounters with mirrored seats whose keys swap: seat 1's key 1 is the game's key 2.
MIRRORED = dataclasses.replace(TWO_COUNTERS, seats=dataclasses.replace(
    TWO_COUNTERS.seats, mirror="left-right", mirror_actions=(0, 2, 1)))


def test_a_player_against_the_ladder_as_json(capsys):
    assert cli.main(["evaluate", "Cycles", "--agent", "eps0.1", "--episodes", "4", "--max-steps", "40", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["game"] == "Cycles" and result["agent"] == "eps0.1" and result["policy"] == "greedy"
    assert [row["opponent"] for row in result["rungs"]] == list(RUNGS)
    for row in result["rungs"]:
        assert {"opponent", "win", "draw", "loss", "margin", "episodes"} <= set(row) and row["episodes"] == 4
        assert row["win"] + row["draw"] + row["loss"] == pytest.approx(1.0)
    assert isinstance(result["elo"], float) and result["ladder"]["random"] == 0 and set(result["ladder"]) == set(RUNGS)
    assert all(len(row["by_seat"]) == 2 for row in result["rungs"])
    table = format_result(result).splitlines()  # what the command prints without --json
    assert table[1].split() == ["opponent", "win", "draw", "loss", "margin", "from", "seat", "0", "/", "1", "ended"]
    assert [line.split()[0] for line in table[2:-1]] == list(RUNGS) and table[-1].startswith("Elo ")


@pytest.mark.parametrize("argv, message", [
    (["Cycles", "--agent", "champion"], "--agent 'champion' is no file and no player"),
    (["Cycles", "--agent", "random", "--episodes", "3"], "--episodes must be even"),
    (["Cycles", "--agent", "random", "--opponents", "random,greedy"], "unknown player 'greedy'"),
    (["Pong", "--agent", "random"], "Pong is a one-player game; two-player games: Cycles"),
    (["Dual", "--agent", "random"], "unknown two-player game 'Dual' (did you mean 'Duel'?)"),
])
def test_bad_arguments_are_named(argv, message, capsys):
    assert cli.main(["evaluate", *argv]) == 1
    assert message in capsys.readouterr().err


@pytest.fixture(scope="module")
def network_file(tmp_path_factory, two_counters_rom):
    """Saves an ActorCritic whose logits are its bias: `prefer` (or none: flat) at 50, output 9 (no
    action of the game) at 60, the rest 0; `planes` other than the game's 5 cut its first kernel.
    50 above the others is more than a Gumbel draw spans (about 21 in float32): sampled play of a
    preferred key is greedy play."""
    from octax_core import make_multi
    from octax_gym.train.checkpoints import save_agents
    from octax_gym.train.networks import ActorCritic

    env, _ = make_multi(TWO_COUNTERS, rom=two_counters_rom)
    params = ActorCritic().init(jax.random.key(0), jnp.zeros((1, *env.observation_shape), jnp.uint8))["params"]
    folder = tmp_path_factory.mktemp("agents")

    def save(name: str, prefer=None, planes: int = 5, view=None):
        logits = params["Dense_1"]
        bias = jnp.zeros_like(logits["bias"]).at[9].set(60.0)
        bias = bias if prefer is None else bias.at[prefer].set(50.0)
        conv = params["ConvTorso_0"]["Conv_0"]
        torso = {**params["ConvTorso_0"], "Conv_0": {**conv, "kernel": conv["kernel"][:, :, :planes]}}
        tree = {"params": {**params, "ConvTorso_0": torso,
                           "Dense_1": {"kernel": jnp.zeros_like(logits["kernel"]), "bias": bias}}}
        return save_agents(folder / name, ["TwoCounters-seed0"], jax.tree.map(lambda x: x[None], tree), view=view)[0]
    return save


def _evaluate(path, rom, game=TWO_COUNTERS, **options):
    return evaluate(game, str(path), opponents="scripted,noop", episodes=4, max_steps=10, rom=rom, **options)


def test_a_saved_network_plays_greedily_its_legal_actions(network_file, two_counters_rom):
    # the scripted player's key (8 a step): a tie with it, a win over noop; output 9, larger, is
    # no action of the game and stays closed
    second = _evaluate(network_file("second", 2), two_counters_rom)
    assert [(r["opponent"], r["win"], r["draw"], r["loss"], r["margin"]) for r in second["rungs"]] == [
        ("scripted", 0.0, 1.0, 0.0, 0.0), ("noop", 1.0, 0.0, 0.0, 24.0)]
    assert second["elo"] is None and second["policy"] == "greedy" and second["agent"].endswith(".msgpack")


def test_sampled_draws_from_the_legal_softmax(network_file, two_counters_rom):
    """Flat logits: greedy holds no-op (the first of the tied) and ties noop; sampled holds keys
    and wins. Sampled in the mirrored env (the mirrored test's match; a flat network and noop are
    the same game mirrored), with output 9, the largest, closed there too."""
    assert _evaluate(network_file("flat"), two_counters_rom)["rungs"][1]["draw"] == 1.0
    sampled = _evaluate(network_file("flat-mirror", view={"mirror": True}), two_counters_rom, MIRRORED, sampled=True,
                        seed=3)
    assert sampled["mirror"] and sampled["policy"] == "sampled" and sampled["rungs"][1]["win"] == 1.0


def test_a_network_of_other_planes_is_refused(network_file, two_counters_rom):
    with pytest.raises(ValueError, match="reads 2 planes; TwoCounters's seats see 5"):
        _evaluate(network_file("two-planes", planes=2), two_counters_rom)


def test_an_agent_trained_with_mirrored_seats_plays_in_the_mirrored_env(network_file, two_counters_rom):
    """TwoCounters with mirrored seats whose keys swap (seat 1's key 1 is the game's key 2): a network
    that holds key 1 scores 4 a step from seat 0 and, seeing the mirror image, 8 from seat 1, against
    noop. Sampled (the sampled test's match), which a preferred key's logit makes greedy play."""
    from octax_core import make_multi
    from octax_gym.cli.evaluate import agent_player

    path = network_file("mirror", 1, view={"mirror": True})
    result = _evaluate(path, two_counters_rom, MIRRORED, sampled=True)
    first, second = (_evaluate(network_file(name, key), two_counters_rom)["rungs"][1] for name, key in
                     (("first", 1), ("second", 2)))
    assert result["mirror"] and [seat["margin"] for seat in result["rungs"][1]["by_seat"]] == \
        [first["by_seat"][0]["margin"], second["by_seat"][1]["margin"]]
    assert "mirrored seats: seat 1 sees the mirror image" in format_result(result)
    plain_env, _ = make_multi(MIRRORED, rom=two_counters_rom)
    with pytest.raises(ValueError, match="trained with mirrored seats .* play it in a mirrored env"):
        agent_player(str(path), plain_env)


def test_the_browser_players_loader_shows_a_mirror_agent_seat_1_as_it_trained(network_file):
    """`octax-gym play`'s env is plain (people see and press the game as it is); a --mirror agent in
    seat 1 (player plane lit) plays its mirror-image action mapped back: key 1 held there is the
    game's key 2 in TwoCounters with swapped mirrored keys, and seat 0 plays as it is."""
    import numpy as np

    from octax_gym.play.agents import load_agent

    path = network_file("mirror", 1, view={"mirror": True})
    agent = load_agent(path, 3, spec=MIRRORED)
    seat0 = np.zeros((5, 32, 64), np.uint8)
    seat1 = seat0.copy()
    seat1[-1] = 1  # the player plane of seat 1
    assert (agent(seat0), agent(seat1)) == (1, 2)
    assert load_agent(network_file("first", 1), 3, spec=MIRRORED)(seat1) == 1  # a plain agent is left alone
    with pytest.raises(ValueError, match=r"trained with mirrored seats \(--mirror\); TwoCounters has none"):
        load_agent(path, 3, spec=TWO_COUNTERS)
