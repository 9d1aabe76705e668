"""The procedural families: every variant renders, assembles and keeps the shared registers."""

import pytest

from octax_core.generate.build import build_variant, register_functions, variant_spec
from octax_core.generate.families import FAMILIES, get_family
from octax_core.generate.render import check_params, render, sprite_width
from octax_core.generate.sample import sample_params
from octax_core.tools.octo import assemble


def test_at_least_three_families():
    assert len(FAMILIES) >= 3
    with pytest.raises(KeyError, match="valid: dodger, catcher, paddle"):
        get_family("pacman")


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_variants_assemble_into_distinct_programs(name):
    family = FAMILIES[name]
    roms = [build_variant(family, sample_params(family, 0, i), f"{name}-{i}").rom for i in range(24)]
    assert len(set(roms)) == 24  # each variant a different program


@pytest.mark.parametrize("name", sorted(FAMILIES))
def test_sampling_is_per_index(name):
    family = FAMILIES[name]
    assert sample_params(family, 3, 7) == sample_params(family, 3, 7)
    assert sample_params(family, 3, 7) != sample_params(family, 4, 7)
    for i in range(16):
        check_params(family, sample_params(family, 0, i))  # the sampler stays inside the ranges


def test_sprite_width_reads_the_rightmost_pixel():
    assert sprite_width([0b10000000]) == 1
    assert sprite_width([0b11000000, 0b10100000]) == 3


def test_render_refuses_params_the_template_is_not_made_for():
    family = get_family("dodger")
    params = sample_params(family, 0, 0)
    with pytest.raises(ValueError, match="fall must be an integer in 1..3, got 9"):
        render(family, {**params, "fall": 9})
    with pytest.raises(ValueError, match="missing: lives"):
        render(family, {k: v for k, v in params.items() if k != "lives"})
    with pytest.raises(ValueError, match="left-aligned"):
        render(family, {**params, "thing": [0b00110000, 0b00110000]})


def test_splits_hold_out_a_parameter_range():
    family = get_family("dodger")
    params = sample_params(family, 0, 0)
    assert family.split_of({**params, family.split: family.held_out[0]}) == "test"
    low, high = family.ranges[family.split]
    kept = [v for v in range(low, high + 1) if v not in family.held_out]
    assert family.split_of({**params, family.split: kept[0]}) == "train"


def test_every_variant_spec_shares_the_family_functions():
    specs = [variant_spec(f"v{i}", "0" * 40) for i in range(3)]
    shared = register_functions()
    assert {(s.score_fn, s.terminated_fn, s.lives_fn) for s in specs} == {shared}
    other = variant_spec("llm", "0" * 40, registers={"score": 3, "lives": None, "end": [7, 2]})
    assert other.score_fn is not shared[0] and other.lives_fn is None
    assert variant_spec("llm2", "0" * 40, registers={"score": 3, "lives": None, "end": [7, 2]}).score_fn is other.score_fn
    with pytest.raises(ValueError, match="score register must be V0..VE"):
        variant_spec("bad", "0" * 40, registers={"score": 15})


def test_the_template_documents_its_registers():
    source = render(get_family("paddle"), sample_params(get_family("paddle"), 0, 1))
    assert ":alias score  v5" in source and ":alias over   vE" in source
    assert assemble(source)
