"""A bounded join at close says which thread it waits for and what that thread is doing."""

from __future__ import annotations

import threading

from engine.joining import join_saying


def test_a_long_wait_names_the_thread_and_its_work_and_gives_up_at_the_bound(capsys):
    release = threading.Event()
    worker = threading.Thread(target=release.wait, name="busy-worker", daemon=True)
    worker.start()
    assert not join_saying(worker, lambda: "InspectLatent", timeout=0.3, say_after=0.1)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 2
    assert "waiting up to 0.3 s for thread 'busy-worker' (InspectLatent)" in err[0]
    assert "thread 'busy-worker' still running after" in err[1] and "(InspectLatent)" in err[1]
    release.set()
    assert join_saying(worker, lambda: "idle", timeout=5.0, say_after=0.1)
    assert not worker.is_alive()


def test_a_quick_join_says_nothing(capsys):
    worker = threading.Thread(target=lambda: None, name="quick")
    worker.start()
    assert join_saying(worker, lambda: "nothing", timeout=5.0, say_after=1.0)
    assert capsys.readouterr().err == ""
