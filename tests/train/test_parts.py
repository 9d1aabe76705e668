"""octax_gym.train's parts on their own: the network's shapes and convolution, the masks on a game's
actions (never an illegal sample, argmax or exploration; a finite entropy), GAE and the Q(lambda)
returns against plain loops, and the agent map's exactness (gradients exact only one agent at a
time: why `agent_map="auto"` maps agents one by one on a CPU)."""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("flax")
import flax.serialization  # noqa: E402
from octax_gym.train import many, ppo, pqn  # noqa: E402
from octax_gym.train.networks import (ACTIONS, LAYERS, ActorCritic, ConvTorso, QNetwork, _sliced_patches,  # noqa: E402
                                      conv_valid, legal_actions, masked, network_for, patches, same_padded)
from host_params import fill_like  # noqa: E402


def test_network_shapes_and_a_fixed_width():
    """Shapes only (`jax.eval_shape`): nothing is computed, so nothing compiles."""
    obs = jax.ShapeDtypeStruct((5, 4, 32, 64), jnp.uint8)
    key = jax.random.key(0)
    features, _ = jax.eval_shape(ConvTorso().init_with_output, key, obs)
    assert features.shape == (5, 1024)
    (logits, value), params = jax.eval_shape(ActorCritic().init_with_output, key, obs)
    assert logits.shape == (5, ACTIONS) == (5, 17) and value.shape == (5,)
    kernels = [params["params"]["ConvTorso_0"][f"Conv_{i}"]["kernel"].shape for i in range(3)]
    assert kernels == [(8, 4, 4, 32), (4, 4, 32, 64), (3, 3, 64, 64)]
    q_params = jax.eval_shape(QNetwork().init, key, obs)
    assert isinstance(network_for(q_params), QNetwork) and isinstance(network_for(params), ActorCritic)
    assert network_for(jax.eval_shape(ActorCritic(3).init, key, obs)).num_actions == 3  # an examples' file


def test_the_papers_layout_reads_the_columns_as_channels_and_is_read_back():
    """--network-layout paper: the (F, 32, 64) frames as one NHWC image (frames x rows, the 64
    columns as channels, SAME padding), as the paper's code hands them to flax; the saved params
    say which layout they are (network_for), also with a multi-task agent's game input."""
    key = jax.random.key(0)
    for frames in (4, 5):  # 5: a self-play agent's player plane
        obs = jax.ShapeDtypeStruct((2, frames, 32, 64), jnp.uint8)
        features, params = jax.eval_shape(ConvTorso("paper").init_with_output, key, obs)
        assert features.shape == (2, 512)
        assert [params["params"][f"Conv_{i}"]["kernel"].shape for i in range(3)] == \
            [(8, 4, 64, 32), (4, 4, 32, 64), (3, 3, 64, 64)]
    obs = jax.ShapeDtypeStruct((2, 4, 32, 64), jnp.uint8)
    for network in (ActorCritic(layout="paper"), QNetwork(layout="paper"), ActorCritic(num_games=3, layout="paper"),
                    ActorCritic(num_games=3)):
        inputs = (obs, jax.ShapeDtypeStruct((2,), jnp.int32)) if getattr(network, "num_games", 0) else obs
        assert network_for(jax.eval_shape(network.init, key, inputs)) == network
    with pytest.raises(ValueError, match="layout must be one of image, paper, got 'columns'"):
        jax.eval_shape(ConvTorso("columns").init, key, obs)


def test_same_padding_then_valid_is_flax_same_convolution():
    """The paper layout's convolutions: `same_padded` then `conv_valid` computes flax's
    nn.Conv(padding="SAME") of every layer, on the shapes the layout meets."""
    import flax.linen as nn

    convs = [nn.Conv(features, kernel, strides, padding="SAME") for features, kernel, strides in LAYERS]
    x = _normal((2, 4, 32, 64), 0)
    params, shape = [], x
    for i, conv in enumerate(convs):
        # any params will do: drawn on the host (tests/host_params.py: no init program to compile)
        shape, shapes = jax.eval_shape(conv.init_with_output, jax.random.key(i), shape)
        params.append(fill_like(shapes["params"], seed=10 + i))

    @jax.jit  # every layer, ours and flax's, in one program
    def both(x, params):
        out = []
        for (_, kernel, strides), conv, layer in zip(LAYERS, convs, params):
            expected = conv.apply({"params": layer}, x)
            out.append((conv_valid(same_padded(x, kernel, strides), layer["kernel"], strides) + layer["bias"], expected))
            x = expected  # the next layer reads flax's output
        return out

    for ours, expected in both(x, params):
        np.testing.assert_allclose(ours, expected, rtol=1e-4, atol=1e-4)


def _normal(shape, seed):
    return jnp.asarray(np.random.default_rng(seed).normal(size=shape).astype(np.float32))


@pytest.mark.parametrize("x_shape, k_shape, strides", [
    ((2, 64, 32, 4), (8, 4, 4, 32), (4, 2)), ((2, 15, 15, 32), (4, 4, 32, 64), (2, 2))])
def test_conv_valid_equals_lax_conv(x_shape, k_shape, strides):
    both = jax.jit(lambda x, kernel: (conv_valid(x, kernel, strides), jax.lax.conv_general_dilated(
        x, kernel, strides, "VALID", dimension_numbers=("NHWC", "HWIO", "NHWC"))))
    ours, expected = both(_normal(x_shape, 1), _normal(k_shape, 2))
    np.testing.assert_allclose(ours, expected, rtol=1e-4, atol=1e-3)


@pytest.mark.parametrize("x_shape, kernel_size, strides", [((3, 64, 32, 4), (8, 4), (4, 2)), ((3, 6, 6, 8), (3, 3), (1, 1))])
def test_patches_are_the_strided_slices_bit_for_bit_both_ways(x_shape, kernel_size, strides):
    """The gather (forward) and the slices' transpose (backward) are the strided slices' own bits,
    so the faster-compiling network trains exactly what the sliced one trained."""
    def forward_and_backward(f, x, cotangent):
        out, transpose = jax.vjp(lambda x: f(x, kernel_size, strides), x)
        return out, transpose(cotangent)[0]
    x = _normal(x_shape, 1)
    cotangent = _normal(jax.eval_shape(lambda x: _sliced_patches(x, kernel_size, strides), x).shape, 2)
    ours, sliced = (jax.jit(functools.partial(forward_and_backward, f))(x, cotangent) for f in (patches, _sliced_patches))
    assert np.array_equal(ours[0], sliced[0]) and np.array_equal(ours[1], sliced[1])


def test_masked_actions_are_never_chosen_and_cost_no_entropy():
    @jax.jit  # the sample, the argmax, the entropy and the exploration in one program
    def chosen(logits, legal):
        log_probs = jax.nn.log_softmax(masked(logits, legal))
        return (jax.random.categorical(jax.random.key(0), masked(logits, legal)), jnp.argmax(masked(logits, legal), axis=1),
                -(jnp.exp(log_probs) * log_probs).sum(-1), pqn.epsilon_greedy(logits, jax.random.key(1), 1.0, legal))

    logits = np.zeros((4000, ACTIONS), np.float32)
    logits[:, 10] = 5.0  # an illegal favourite
    sample, greedy, entropy, explored = chosen(logits, legal_actions(3))
    assert int(np.max(sample)) < 3 and set(np.unique(sample).tolist()) == {0, 1, 2}
    assert int(np.max(greedy)) < 3
    np.testing.assert_allclose(entropy, np.log(3), rtol=1e-6)
    assert set(np.unique(explored).tolist()) == {0, 1, 2}


def test_gae_matches_a_loop():
    rng = np.random.default_rng(0)
    steps, envs, gamma, lam = 6, 3, 0.9, 0.8
    reward, value = rng.normal(size=(steps, envs)), rng.normal(size=(steps, envs))
    done = rng.random((steps, envs)) < 0.3
    last_value = rng.normal(size=envs)
    advantages, targets = ppo.gae(jnp.asarray(reward, jnp.float32), jnp.asarray(done), jnp.asarray(value, jnp.float32),
                                  jnp.asarray(last_value, jnp.float32), gamma, lam)
    expected, running = np.zeros((steps, envs)), np.zeros(envs)
    for t in reversed(range(steps)):
        next_value = last_value if t == steps - 1 else value[t + 1]
        delta = reward[t] + gamma * next_value * ~done[t] - value[t]
        running = delta + gamma * lam * ~done[t] * running
        expected[t] = running
    np.testing.assert_allclose(advantages, expected, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(targets, expected + value, rtol=1e-5, atol=1e-5)


def test_q_lambda_targets_match_a_loop():
    rng = np.random.default_rng(1)
    steps, envs, gamma, lam = 5, 2, 0.9, 0.7
    reward, q_max = rng.normal(size=(steps, envs)), rng.normal(size=(steps, envs))
    done = rng.random((steps, envs)) < 0.3
    last_q = rng.normal(size=envs)
    targets = pqn.q_lambda_targets(*(jnp.asarray(a, jnp.float32) for a in (reward,)), jnp.asarray(done),
                                   jnp.asarray(q_max, jnp.float32), jnp.asarray(last_q, jnp.float32), gamma, lam)
    expected, next_return, next_q = np.zeros((steps, envs)), last_q, last_q
    for t in reversed(range(steps)):
        expected[t] = reward[t] + gamma * ~done[t] * (lam * next_return + (1 - lam) * next_q)
        next_return, next_q = expected[t], q_max[t]
    np.testing.assert_allclose(targets, expected, rtol=1e-5, atol=1e-5)


def _bits_of_agent(fn, params, obs, agent_map):
    both = jax.jit(many.over_agents(fn, 4, agent_map))(params, obs)
    lone = jax.jit(fn)(jax.tree.map(lambda x: x[1], params), obs[1])
    return all(np.array_equal(np.asarray(a)[1], np.asarray(b)) for a, b in zip(jax.tree.leaves(both),
                                                                                jax.tree.leaves(lone)))


def test_agent_map_one_by_one_is_bit_exact_where_vmap_is_not():
    network = QNetwork()
    obs = jnp.asarray(np.random.default_rng(0).random((4, 8, 4, 32, 64)) < 0.2, jnp.uint8)  # 4 agents x 8 frames
    # 4 agents' params drawn on the host (tests/host_params.py: no init program to compile)
    params = fill_like(jax.eval_shape(network.init, jax.random.key(0), obs[0, :1]), seed=3, batch=(4,))

    def grad(p, o):
        return jax.grad(lambda p: jax.nn.log_softmax(network.apply(p, o)).mean())(p)

    assert _bits_of_agent(grad, params, obs, "map")
    assert not _bits_of_agent(grad, params, obs, "vmap")  # if this ever holds, "vmap" could be the CPU default


def test_a_game_without_a_reference_score_is_named_left_out_and_written_as_null(tmp_path):
    """Tetris has no reference score, so no normalized score: the IQM over games is the other
    games', says which were left out, and summary.json stays strict JSON (null, not NaN)."""
    import json

    from octax_gym.train import report

    rows = [{"game": g, "seed": s, "step": 8, "eval_mean_return": r + s, "eval_greedy_return": r}
            for g, r in (("Airplane", 2.0), ("Tetris", 0.0)) for s in (0, 1)]
    summary = report.summarize(rows, ["Airplane", "Tetris"], [0, 1])
    assert summary["normalized_iqm"]["games"] == ["Airplane"]
    assert summary["normalized_iqm"]["left_out"] == ["Tetris"]
    assert "not Tetris" in report.table(summary)
    report.write(summary, tmp_path / "summary.json")
    text = (tmp_path / "summary.json").read_text()
    strict = json.loads(text, parse_constant=lambda name: pytest.fail(f"summary.json holds {name}"))
    assert strict["games"]["Tetris"]["normalized_iqm"] is None


def test_epsilon_decays_over_the_first_tenth_then_stays():
    from octax_gym.train import preset

    config = preset("cpu", "pqn", num_envs=8, num_steps=10, num_minibatches=2, total_steps=8 * 10 * 100)
    assert float(config.epsilon(0)) == 1.0
    assert float(config.epsilon(5)) == pytest.approx(1.0 - 0.95 * 0.5)
    assert float(config.epsilon(10)) == pytest.approx(0.05)
    assert float(config.epsilon(99)) == pytest.approx(0.05)


def test_any_over_agents_is_shared_by_vmapped_agents_so_a_cond_stays_a_branch():
    flags = np.array([[False, False], [False, True], [False, False]])
    shared = many.over_agents(lambda f: many.any_over_agents(f, True), 3, "vmap")(flags)
    assert shared.tolist() == [True, True, True]  # agent 1's truncation is every agent's predicate
    assert many.over_agents(lambda f: many.any_over_agents(f, False), 1)(flags[1:2]).tolist() == [True]

    def step(f):
        return jax.lax.cond(many.any_over_agents(f, True), lambda: f.sum(), lambda: -1)

    jaxpr = str(jax.make_jaxpr(many.over_agents(step, 3, "vmap"))(flags))
    assert "cond[" in jaxpr and "select_n" not in jaxpr  # with a per-agent predicate vmap makes it a select
    per_agent = str(jax.make_jaxpr(jax.vmap(lambda f: jax.lax.cond(f.any(), lambda: f.sum(), lambda: -1)))(flags))
    assert "select_n" in per_agent


def test_learn_passes_over_the_whole_rollout_each_epoch_and_counts_the_update():
    from octax_gym.train import preset, rollout

    config = preset("cpu", "ppo", num_envs=3, num_steps=4, num_minibatches=3, update_epochs=2, learning_rate=0.1,
                    total_steps=12)
    batch = jnp.arange(12.0).reshape(4, 3)  # (num_steps, lanes)

    def loss(params, minibatch):
        return jnp.mean((params["w"] - minibatch) ** 2), {"mean": minibatch.mean(), "size": minibatch.size}

    optimizer = rollout.make_optimizer(config)
    params = {"w": jnp.zeros(())}
    runner = rollout.RunnerState(params, optimizer.init(params), None, None, None, jax.random.key(0), jnp.int32(0),
                                 jnp.int32(0))
    learned, stats = jax.jit(rollout.make_learn(config, optimizer, loss))(runner, batch)
    # Every epoch splits all 12 samples into 3 minibatches of 4, so their means average to the batch's.
    assert float(stats["mean"]) == pytest.approx(5.5) and float(stats["size"]) == 4
    assert 0 < float(learned.params["w"]) <= 6 * 0.1 + 1e-6  # 6 Adam steps of at most lr each, towards 5.5
    assert int(learned.updates) == 1
    assert not np.array_equal(jax.random.key_data(learned.key), jax.random.key_data(runner.key))
    # twice the lanes (self-play's two seats): the same minibatch count, each twice as large
    _, stats = jax.jit(rollout.make_learn(config, optimizer, loss))(runner, jnp.arange(24.0).reshape(4, 6))
    assert float(stats["size"]) == 8 and float(stats["mean"]) == pytest.approx(11.5)


def test_an_agent_file_records_how_its_agent_sees_the_game(tmp_path):
    """A --mirror run's agents carry {"mirror": True} beside their params (`TrainConfig.agent_view`),
    and a paper-layout run's its layout and planes (which its params do not show), read back by
    `jax_policy.load_agent`; a plain run's files hold their params alone, as before."""
    from octax_gym import jax_policy
    from octax_gym.train import TrainConfig
    from octax_gym.train.checkpoints import save_agents

    def saved_params(network):
        shapes = jax.eval_shape(network.init, jax.random.key(0), jax.ShapeDtypeStruct((1, 5, 32, 64), jnp.uint8))
        rng = np.random.default_rng(0)
        params = jax.tree.map(lambda s: rng.normal(size=s.shape).astype(np.float32), shapes)
        return params, jax.tree.map(lambda x: x[None], params)

    params, stacked = saved_params(ActorCritic())
    plain_config = TrainConfig(games=("Cycles",))
    mirrored = TrainConfig(algorithm="selfplay", games=("Cycles",), env_overrides=(("mirror", True),))
    assert mirrored.agent_view(5) == {"mirror": True} and plain_config.agent_view(5) == {}
    [plain] = save_agents(tmp_path / "plain", ["a"], stacked, view=plain_config.agent_view(5))
    [seen] = save_agents(tmp_path / "mirror", ["a"], stacked, view=mirrored.agent_view(5))
    assert plain.read_bytes() == flax.serialization.to_bytes(jax.tree.map(lambda x: x[0], stacked))  # as of old
    for path, mirror in ((plain, False), (seen, True)):
        loaded, network = jax_policy.load_agent(path)
        assert network == ("actor_critic", 5, ACTIONS, mirror, "image") and jax_policy.load_params(path).keys() == {"params"}
        assert all(np.array_equal(a, b) for a, b in zip(jax.tree.leaves(loaded), jax.tree.leaves(params)))
    paper_params, paper_stacked = saved_params(QNetwork(layout="paper"))
    paper = TrainConfig(algorithm="pqn", network_layout="paper")
    assert paper.agent_view(5) == {"layout": "paper", "planes": 5}
    [columns] = save_agents(tmp_path / "paper", ["a"], paper_stacked, view=paper.agent_view(5))
    assert jax_policy.load_agent(columns)[1] == ("q_network", 5, ACTIONS, False, "paper")
    [unknown] = save_agents(tmp_path / "new", ["a"], stacked, view={"colours": 4})
    with pytest.raises(ValueError, match=r"holds \['colours'\], which this version does not know \(it knows "
                                         r"\['mirror', 'layout', 'planes'\]\)"):
        jax_policy.load_agent(unknown)
    [wrong] = save_agents(tmp_path / "wrong", ["a"], stacked, view={"layout": "paper", "planes": 5})
    with pytest.raises(ValueError, match="its view record says layout 'paper', its params are of layout 'image'"):
        jax_policy.load_agent(wrong)
