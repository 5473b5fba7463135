"""``--set key=value`` parsing (engine.config.parse_overrides)."""

from __future__ import annotations

import dataclasses

import pytest

from engine.config import parse_overrides
from engine.errors import UserError


@dataclasses.dataclass
class _Settings:
    lr: float = 0.1
    iterations: int = 10
    name: str = "x"
    fast: bool = True
    channels: list = dataclasses.field(default_factory=list)


def test_plain_numbers_and_lists_are_typed_by_the_field():
    got = parse_overrides(_Settings, ["lr=3e-4", "iterations=+20", "name=a b", "fast=false", "channels=[1, 2]"])
    assert got == {"lr": 3e-4, "iterations": 20, "name": "a b", "fast": False, "channels": [1, 2]}
    assert parse_overrides(_Settings, ["lr=.5"]) == {"lr": 0.5}
    assert parse_overrides(_Settings, ["lr=2."]) == {"lr": 2.0}


@pytest.mark.parametrize(
    "item", ["lr=٣", "lr=1_0", "iterations=1_0", "iterations=３", "iterations=2.0", "lr=0x10", "lr="]
)
def test_numbers_python_would_also_read_are_refused(item):
    key, raw = item.split("=", 1)
    with pytest.raises(UserError, match=f"--set {key}={raw}: not a valid"):
        parse_overrides(_Settings, [item])


def test_an_unknown_key_is_named():
    with pytest.raises(UserError, match="--set speed: unknown setting"):
        parse_overrides(_Settings, ["speed=1"])
