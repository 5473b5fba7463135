"""The engine in its own process (engine.studio.process): the thread's contract across a
process boundary, shutdown without orphans, and failures reported instead of hidden."""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from engine.studio import commands as cmd
from engine.studio.process import EngineProcess, HistorySender
from engine.studio.session import Session
from engine.studio.thread import EngineThread
from tests.conftest import REPO
from tests.engine.test_studio_thread import wait_for

#: A spawned child imports torch and the methods first: slow on a loaded 2-core machine.
START_S = 120.0


def exploding_method(name):
    """A picklable factory (the child imports it by name) whose method always fails."""
    from tests.engine.test_studio_thread import Exploding

    return Exploding()


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie (exited, not yet reaped) counts as gone
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.fixture
def proc_session(synthetic_motion):
    session = Session(method="ik")
    session.set_motion(synthetic_motion)
    engine = session.start_engine(process=True)
    yield session, engine
    session.shutdown()
    assert not engine.is_alive(), "the engine process or its receiver outlived shutdown"


def test_process_engine_plays_every_frame_and_rebuilds_the_history(proc_session):
    session, engine = proc_session
    assert isinstance(engine, EngineProcess)
    wait_for(lambda: engine.latest is not None, START_S)
    session.set_playback(loop=False)
    session.play()
    wait_for(lambda: engine.latest.frame >= 60, 60)
    snap = engine.latest
    assert snap.positions.shape == (22, 3) and not snap.positions.flags.writeable
    assert snap.frames_skipped == 0 and snap.pace == "every_frame"
    frames = [r.frame for r in snap.history]
    # sent as increments, rebuilt whole: every solved frame of this run, in order
    assert frames == list(range(frames[0], snap.frame + 1)) and len(frames) >= 50
    assert snap.losses and all(np.isfinite(v) for v in snap.losses[-1].values())


def test_edits_reach_the_process_like_the_thread(proc_session):
    session, engine = proc_session
    wait_for(lambda: engine.latest is not None and engine.latest.losses, START_S)
    joint = next(iter(session.sensors))
    seq = engine.latest.seq
    session.sensors.edit(joint, enabled=False)
    wait_for(lambda: engine.latest.seq > seq and joint not in engine.latest.target_joints, 30)
    session.constraints.add("pin", joint="lwrist", position=(0.3, 0.2, 1.0))
    wait_for(lambda: any(name == "pin" for name, _ in engine.latest.gizmos), 30)


def test_a_failing_method_is_reported_in_the_snapshot(synthetic_motion):
    session = Session(method="boom")
    session.set_motion(synthetic_motion)
    engine = session.start_engine(method_factory=exploding_method, process=True)
    try:
        wait_for(lambda: engine.latest is not None, START_S)
        session.play()  # the method raises at frame 3, returns NaN at frame 4
        wait_for(lambda: engine.latest.error or any("boom" in e for e in engine.latest.recent_errors), 30)
        assert any("RuntimeError: boom" in e for e in engine.latest.recent_errors)
    finally:
        session.shutdown()
    assert not engine.is_alive()


def test_a_child_that_dies_is_reported(synthetic_motion):
    session = Session(method="ik")
    session.set_motion(synthetic_motion)
    engine = session.start_engine(process=True)
    try:
        wait_for(lambda: engine.latest is not None, START_S)
        os.kill(engine._process.pid, signal.SIGKILL)
        wait_for(lambda: engine.failure != "", 10)
        assert "stopped unexpectedly" in engine.failure
    finally:
        session.shutdown()
    assert not engine.is_alive()


def test_stop_before_the_child_is_ready_terminates_it_quickly():
    engine = EngineProcess()
    engine.start()
    t0 = time.monotonic()
    engine.stop(timeout=0.5)  # the child is still importing torch: no loop reads the queue yet
    assert not engine.is_alive() and time.monotonic() - t0 < 10


def test_the_child_exits_when_its_parent_dies(tmp_path):
    """No orphan solver: a window killed outright takes its engine process with it."""
    script = (
        "import sys, time\n"
        "from engine.studio.process import EngineProcess\n"
        "e = EngineProcess(); e.start(); print(e._process.pid, flush=True); time.sleep(60)\n"
    )
    parent = subprocess.Popen(
        [sys.executable, "-c", script],
        cwd=REPO,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(REPO)},
    )
    child = int(parent.stdout.readline())
    assert alive(child)
    parent.kill()
    parent.wait()
    wait_for(lambda: not alive(child), 15)


@dataclasses.dataclass(frozen=True)
class _Snap:
    history: tuple = ()


def _send_after_the_window_closed_its_end() -> None:
    reader, writer = mp.Pipe(duplex=False)
    reader.close()
    HistorySender(writer)(_Snap())
    raise AssertionError("the snapshot went to a closed pipe without a word")


def test_a_solver_whose_window_is_gone_ends_quietly():
    """A killed window closes its end of the pipe; the solver's next snapshot must end
    the solver's process cleanly (exit 0, nothing on stderr), not with a traceback."""
    child = mp.get_context("fork").Process(target=_send_after_the_window_closed_its_end)
    child.start()
    child.join(30)
    assert child.exitcode == 0


def test_a_source_that_cannot_cross_moves_the_engine_into_a_thread(synthetic_motion):
    """A live tracker stream (sockets, threads) stays in the window's process."""
    import threading

    from engine.studio.clip_source import ClipSource

    class LiveLike(ClipSource):
        live = False

        def __init__(self, motion):
            super().__init__(motion)
            self.lock = threading.Lock()  # what makes a real live source unpicklable

    session = Session(method="ik")
    session.set_motion(synthetic_motion)
    engine = session.start_engine(process=True)
    try:
        assert not EngineProcess.can_send(cmd.SetSource(LiveLike(synthetic_motion)))
        session.set_source(LiveLike(synthetic_motion), "live")
        assert isinstance(session.engine, EngineThread) and not engine.is_alive()
        wait_for(lambda: session.latest is not None, 30)
    finally:
        session.shutdown()
    assert not session.engine.is_alive()


def test_a_dead_engine_is_replaced_by_one_with_the_whole_session_edits_made_meanwhile_included(synthetic_motion):
    session = Session(method="ik")
    session.set_motion(synthetic_motion)
    engine = session.start_engine(process=True)
    new = None
    try:
        wait_for(lambda: engine.latest is not None, START_S)
        os.kill(engine._process.pid, signal.SIGKILL)
        wait_for(lambda: engine.failure != "", 10)
        session.sensors.set_preset("4")  # edits while no engine runs: sent to the dead one
        session.constraints.add("pin", joint="lwrist", position=(0.3, 0.2, 1.0))
        session.seek(33)
        new = session.restart_engine()
        assert isinstance(new, EngineProcess) and new is not engine and session.engine is new
        assert not engine.is_alive()
        wait_for(lambda: new.latest is not None and new.latest.frame == 33, START_S)
        snap = new.latest
        assert set(snap.target_joints) == {s.joint for s in session.sensors.values()} and len(snap.target_joints) == 4
        assert any(name == "pin" for name, _ in snap.gizmos) and snap.method == "ik"
    finally:
        session.shutdown()
    assert new is not None and not new.is_alive()
