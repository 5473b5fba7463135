"""When the studio restarts a dead solver (engine/studio/restarts.py)."""

from __future__ import annotations

from engine.studio.restarts import RestartPolicy


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_the_third_death_within_a_minute_stops_the_restarts_and_says_why():
    clock = Clock()
    policy = RestartPolicy(clock=clock)
    for t in (0.0, 30.0):
        clock.now = t
        assert policy.died() and policy.stopped == ""
    clock.now = 59.0
    assert not policy.died()
    assert policy.stopped == "the solver process stopped 3 times within 60 s, so it is not restarted again"
    clock.now = 500.0
    assert not policy.died()  # stopped for good: the user restarts the studio


def test_deaths_further_apart_than_a_minute_are_always_restarted():
    clock = Clock()
    policy = RestartPolicy(clock=clock)
    for t in (0.0, 50.0, 111.0, 170.0, 240.0):
        clock.now = t
        assert policy.died(), t
