"""Fixtures for the core tests: the per-opcode `chip` builder (see chip_builder.py)."""

from chip_builder import chip  # noqa: F401  (a pytest fixture, used by test_ops_*.py)
