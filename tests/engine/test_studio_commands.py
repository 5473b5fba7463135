"""Every engine command has a handler, found by the command's class; one without is
refused loudly."""

from __future__ import annotations

import dataclasses
import inspect
import threading

import pytest

from engine.studio import commands as cmd
from engine.studio.thread import EngineThread


def _defined_classes() -> list[type]:
    """The classes ``engine/studio/commands.py`` defines (so a new one is covered)."""
    return [c for _, c in inspect.getmembers(cmd, inspect.isclass) if c.__module__ == cmd.__name__]


def _commands() -> list[type[cmd.Command]]:
    return [c for c in _defined_classes() if c is not cmd.Command]


def test_the_module_defines_the_commands():
    names = {c.__name__ for c in _commands()}
    assert {"SetMotion", "SetConstraints", "Seek", "Play", "Pause", "Stop", "SetSource"} <= names


@pytest.mark.parametrize("command", _commands(), ids=lambda c: c.__name__)
def test_every_command_is_a_frozen_command_with_its_own_handler(command):
    assert issubclass(command, cmd.Command), f"{command.__name__} does not derive from Command"
    assert dataclasses.is_dataclass(command) and command.__dataclass_params__.frozen
    assert command in cmd.HANDLERS, f"EngineThread has no @handles({command.__name__}) method"
    handler = cmd.HANDLERS[command]
    assert getattr(EngineThread, handler.__name__) is handler, "handlers are EngineThread methods"
    assert not hasattr(threading.Thread, handler.__name__), "a handler must not hide a Thread method"


def test_an_unknown_command_is_refused_at_submit():
    @dataclasses.dataclass(frozen=True)
    class Jump(cmd.Command):
        frame: int = 0

    worker = EngineThread(lambda name: None)
    with pytest.raises(TypeError, match="no handler for 'Jump'"):
        worker.submit(Jump())
    with pytest.raises(TypeError, match="no handler for 'tuple'"):
        worker.submit(("seek", 3))
    assert worker._queue.empty()


def test_an_unknown_command_on_the_queue_is_reported_and_the_loop_goes_on():
    class Jump(cmd.Command):
        pass

    worker = EngineThread(lambda name: None)
    worker._apply(Jump())
    assert "no handler for command Jump" in worker._pending_error and not worker._stopping
    worker._apply(cmd.Stop())
    assert worker._stopping


def test_a_second_handler_for_a_command_is_an_error():
    with pytest.raises(TypeError, match="two engine handlers for Seek"):
        cmd.handles(cmd.Seek)(lambda thread, c, was_dirty: None)
