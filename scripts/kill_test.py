"""Kill test (issue 51, docs/reliability.md): an authoring session in the studio and a pose
window, driven by real Qt input (drags on the 3D views, keys, clicks on the panels),
killed with SIGKILL at random moments.

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/kill_test.py studio --kills 10
    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/kill_test.py engine --kills 10

``studio``: the studio process is killed ``--kills`` times, each after a random 2-12 s of
editing, and started again, as ``dragposer-studio gui`` starts: it offers the left
session and the script answers *Recover last session*. Each start must restore exactly
what the autosave files held (the studio's scene, the pose window's document), and what
it restores must be a state the killed session really had no more than ``--max-loss``
(5) seconds before the kill: every edit made earlier is kept. A last start quits
cleanly and must leave no autosave file.

``engine``: one studio session whose solver process is killed ``--kills`` times (at least
31 s apart: three deaths within a minute stop the restarts, by design). After each kill
the window must start a new solver by itself and that solver must show the session as it
is (frame, method, sensors, constraints), edits made meanwhile included.

The session journals every state its windows pass through (a digest of the studio's
scene and of the pose window's document, with the time) to a file, flushed at once, so a
kill loses none of it; the checks compare that journal with what the next start
recovers. Exit status 0 when every kill passed; the last line reads
``kill-test studio kills=10 passed=10 ...``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
#: A window's state digest when it has nothing unsaved (no autosave file then).
CLEAN = "clean"
#: Joints the author drags in the pose window.
DRAGGED = ("lwrist", "rwrist", "lelbow", "relbow", "upperneck", "lankle")


def digest(doc: Any) -> str:
    return hashlib.sha1(json.dumps(doc, sort_keys=True, allow_nan=False).encode()).hexdigest()[:16]


# -- the session (a child process) -------------------------------------------------------


class Journal:
    """Appends one JSON line per event; each line is written through at once (a SIGKILL
    keeps everything written before it: the kernel has it)."""

    def __init__(self, path: Path) -> None:
        self.file = open(path, "a", buffering=1)  # noqa: SIM115 (open for the process's life)

    def write(self, **entry: Any) -> None:
        self.file.write(json.dumps({"t": time.time(), "pid": os.getpid(), **entry}) + "\n")
        self.file.flush()


class Author:
    """Random authoring edits through real input on ``studio`` and ``pose``; every state
    the windows pass through goes to ``journal``."""

    def __init__(self, studio: Any, pose: Any, journal: Journal, rng: random.Random) -> None:
        self.w, self.pose, self.journal, self.rng = studio, pose, journal, rng
        self.last: tuple[str, str] | None = None
        self.paused = False

    def state(self) -> tuple[str, str]:
        from engine.authoring.recovery import document

        studio = CLEAN if self.w.undo.is_clean() else digest(self.w.session.to_scene())
        pose = digest(document(self.pose.session)) if self.pose.session.dirty else CLEAN
        return studio, pose

    def note(self, what: str = "") -> None:
        """Journal the windows' state when it changed."""
        now = self.state()
        if now != self.last:
            self.last = now
            self.journal.write(event="state", studio=now[0], pose=now[1], edit=what)

    def step(self) -> None:
        if self.paused:
            return
        edits = [self.studio_key, self.studio_pin, self.studio_sensor, self.studio_setting, self.undo_studio]
        edits += [self.pose_drag, self.pose_drag, self.pose_key, self.pose_frame, self.undo_pose]
        edit = self.rng.choice(edits)
        edit()
        self.note(edit.__name__)

    # the studio
    def studio_key(self) -> None:
        from PyQt6.QtCore import Qt
        from PyQt6.QtTest import QTest

        self.w.activateWindow()
        QTest.keyClick(self.w.viewport.plotter, self.rng.choice([Qt.Key.Key_Right, Qt.Key.Key_Left]))

    def studio_pin(self) -> None:
        """Ctrl+drag from a joint: a pin constraint (at most three; then a plain drag
        of the view)."""
        from engine import skeleton as sk
        from tests.app.gui_helpers import mouse_drag, pixel_of

        snap = self.w.session.latest
        if snap is None:
            return
        view = self.w.viewport
        view.plotter.render()
        joint = self.rng.choice(("lelbow", "relbow", "lknee", "rknee"))
        x, y = pixel_of(view, snap.positions[sk.JOINT_INDEX[joint]])
        ctrl = len(self.w.session.constraints) < 3
        dx, dy = self.rng.uniform(-40, 40), self.rng.uniform(-40, 40)
        mouse_drag(view, (x, y), (x + dx, y + dy), ctrl=ctrl, steps=4, on_move=lambda: self.note("drag"))

    def studio_sensor(self) -> None:
        from PyQt6.QtWidgets import QCheckBox

        boxes = [b for b in self.w.sensor_panel.findChildren(QCheckBox) if b.isVisible() and b.isEnabled()]
        if boxes:
            self.rng.choice(boxes).click()

    def studio_setting(self) -> None:
        from PyQt6.QtWidgets import QAbstractSpinBox

        boxes = [b for b in self.w.optimizer_panel.findChildren(QAbstractSpinBox) if b.isVisible() and b.isEnabled()]
        if boxes:
            self.rng.choice(boxes).stepBy(self.rng.choice([-1, 1]))

    def undo_studio(self) -> None:
        from PyQt6.QtCore import Qt
        from PyQt6.QtTest import QTest

        self.w.activateWindow()
        QTest.keyClick(self.w.viewport.plotter, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)

    # the pose window
    def pose_drag(self) -> None:
        from engine import skeleton as sk
        from tests.app.gui_helpers import mouse_drag, pixel_of

        view = self.pose.viewport
        view.plotter.render()
        joint = self.rng.choice(DRAGGED)
        x, y = pixel_of(view, self.pose.mode.pose.positions[sk.JOINT_INDEX[joint]])
        dx, dy = self.rng.uniform(-35, 35), self.rng.uniform(-35, 35)
        mouse_drag(view, (x, y), (x + dx, y + dy), steps=4, on_move=lambda: self.note("drag"))

    def _pose_key(self, key: Any, mods: Any = None) -> None:
        from PyQt6.QtCore import Qt
        from PyQt6.QtTest import QTest

        self.pose.activateWindow()
        QTest.keyClick(self.pose.viewport.plotter, key, mods or Qt.KeyboardModifier.NoModifier)

    def pose_key(self) -> None:
        from PyQt6.QtCore import Qt

        self._pose_key(Qt.Key.Key_K)  # a key at the current frame

    def pose_frame(self) -> None:
        from PyQt6.QtCore import Qt

        for _ in range(self.rng.randint(1, 8)):
            self._pose_key(self.rng.choice([Qt.Key.Key_Right, Qt.Key.Key_Left]))

    def undo_pose(self) -> None:
        from PyQt6.QtCore import Qt

        self._pose_key(Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)


class EngineCheck:
    """After the window replaced a dead solver: wait for the new one's snapshot to show
    the session (frame, method, sensors, constraints), pausing the author meanwhile, and
    journal the outcome."""

    def __init__(self, w: Any, author: Author, journal: Journal, timeout_s: float = 240.0) -> None:
        self.w, self.author, self.journal, self.timeout_s = w, author, journal, timeout_s
        self.engine = w.engine
        self.since: float | None = None
        self.journal.write(event="engine", engine_pid=self.pid())

    def pid(self) -> int | None:
        process = getattr(self.w.engine, "_process", None)
        return None if process is None else process.pid

    def matches(self) -> str:
        """What the new solver's newest snapshot still lacks ("" when it shows the session)."""
        s, snap = self.w.session, self.w.session.latest
        if snap is None:
            return "no snapshot yet"
        lacks = []
        if snap.frame != s.frame:
            lacks.append(f"frame {snap.frame} != {s.frame}")
        if snap.method != s.method:
            lacks.append(f"method {snap.method} != {s.method}")
        on = {c.joint for c in s.sensors.values() if c.enabled and not c.lost_at(s.frame)}
        if set(snap.target_joints) != on:
            lacks.append(f"sensors {sorted(snap.target_joints)} != {sorted(on)}")
        names = {name for name, _ in snap.gizmos}
        missing = [c.name for c in s.constraints if c.name not in names]
        if missing:
            lacks.append(f"constraints {missing} not drawn")
        return "; ".join(lacks)

    def tick(self) -> None:
        if self.w.engine is not self.engine:  # the window restarted its solver
            self.engine = self.w.engine
            self.since = time.monotonic()
            watch = self.w.drawing.engine_watch
            self.journal.write(event="engine", engine_pid=self.pid(), restarts=watch.restarts, line=watch.line)
        if self.since is None:
            return
        if self.w.session.latest is not None:
            self.author.paused = True  # the new solver is up: let it catch up with the session
        lacks = self.matches()
        waited = time.monotonic() - self.since
        if not lacks or waited > self.timeout_s:
            self.journal.write(event="engine_ok" if not lacks else "engine_bad", waited_s=round(waited, 2), lacks=lacks)
            self.since = None
            self.author.paused = False


def session_main(a: argparse.Namespace) -> int:
    """One start of the studio: recover what the last one left, open a pose window, edit
    until killed (or until the file ``STATE/quit`` appears: then quit cleanly)."""
    from PyQt6.QtCore import QSettings, QTimer
    from PyQt6.QtWidgets import QApplication, QMessageBox

    from app import autosave
    from app.authoring_actions import open_pose_window
    from app.main import start_autosave
    from app.main_window import MainWindow
    from engine.autosave import left_sessions

    state, journal = Path(a.state), Journal(Path(a.journal))
    app = QApplication(sys.argv[:1])
    QMessageBox.question = lambda *_a, **_k: QMessageBox.StandardButton.Discard  # the clean quit discards
    problems: list[str] = []
    w = MainWindow(
        method=a.method, settings=QSettings(str(state / "studio.ini"), QSettings.Format.IniFormat), engine=a.engine
    )
    w.show_error = lambda title, text: problems.append(f"{title}: {text}")  # type: ignore[method-assign]
    # as `gui` starts: the clip, its start is not an edit, the autosave, then the offer
    if not w.files.open_path(a.clip, ask=False):
        raise SystemExit(f"cannot open {a.clip}")
    w.undo.set_clean()
    w.resize(1400, 900)
    w.show()
    files = start_autosave(w, state)
    assert files is not None
    left = left_sessions(state)
    found = {}
    if left:
        found = {name: digest(left[0].read(name)[0]) for name in left[0].documents}
    deadline = time.monotonic() + 300
    while w.session.latest is None and time.monotonic() < deadline:
        app.processEvents()
        time.sleep(0.02)
    w.session.pause()
    box = autosave.offer(w, left)
    if box is not None:
        next(b for b in box.buttons() if b.text() == "Recover last session").click()
    poses = [p for p in w.pose_windows if p.isVisible()]
    pose = poses[0] if poses else open_pose_window(w, 1.75, from_clip=False)
    pose.resize(1000, 700)
    w.activateWindow()
    author = Author(w, pose, journal, random.Random(a.seed))
    studio_now, pose_now = author.state()
    journal.write(event="started", left=found, studio=studio_now, pose=pose_now, problems=problems, poses=len(poses))
    author.note("start")
    engine = EngineCheck(w, author, journal)
    timer = QTimer(interval=a.edit_ms)
    timer.timeout.connect(author.step)
    timer.start()
    watch = QTimer(interval=100)
    watch.timeout.connect(engine.tick)

    def maybe_quit() -> None:
        if (state / "quit").exists():
            timer.stop()
            watch.stop()
            w.close()  # asks each window, answered Discard, then closes them
            app.processEvents()
            files.close()  # what `gui` does after a clean quit
            journal.write(event="quit", problems=problems)
            app.quit()

    watch.timeout.connect(maybe_quit)
    watch.start()
    app.exec()
    return 0


# -- the checks (the parent process) -----------------------------------------------------


def read_journal(path: Path) -> list[dict[str, Any]]:
    if not path.exists():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


def wait_for(path: Path, event: str, pid: int, timeout_s: float, after: int = 0, proc: Any = None) -> dict:
    """The first journal entry ``event`` (or one of the events ``a|b``) of process
    ``pid`` after line ``after``."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        for e in read_journal(path)[after:]:
            if e["event"] in event.split("|") and e["pid"] == pid:
                return e
        if proc is not None and proc.poll() is not None:
            raise RuntimeError(f"the session ended (exit {proc.returncode}) before '{event}'")
        time.sleep(0.2)
    raise TimeoutError(f"no '{event}' from the session within {timeout_s:.0f} s")


def check_recovery(killed: list[dict], kill_t: float, started: dict, max_loss: float) -> list[str]:
    """What went wrong in recovering the session journalled in ``killed`` (killed at
    ``kill_t``) into the start ``started``; empty when nothing."""
    bad = list(started["problems"])
    left = started["left"]
    pose_docs = [k for k in left if k != "studio"]
    if len(pose_docs) > 1:
        bad.append(f"{len(pose_docs)} pose documents left, the session had one pose window")
    expected = {"studio": left.get("studio", CLEAN), "pose": left[pose_docs[0]] if pose_docs else CLEAN}
    states = [e for e in killed if e["event"] == "state"]
    for doc in ("studio", "pose"):
        got = started[doc]
        if got != expected[doc]:
            bad.append(f"{doc}: recovered {got}, the autosave file held {expected[doc]}")
        at = max((i for i, e in enumerate(states) if e[doc] == got), default=None)
        if at is None:
            bad.append(f"{doc}: recovered {got}, a state the killed session never had")
            continue
        lost = next((e for e in states[at + 1 :] if e[doc] != got), None)
        if lost is not None and kill_t - lost["t"] > max_loss:
            bad.append(f"{doc}: lost an edit made {kill_t - lost['t']:.1f} s before the kill ({lost['edit']})")
    return bad


def loss_s(killed: list[dict], kill_t: float, started: dict) -> float:
    """Age at the kill of the oldest edit that did not come back (0: none lost)."""
    states = [e for e in killed if e["event"] == "state"]
    ages = [0.0]
    for doc in ("studio", "pose"):
        at = max((i for i, e in enumerate(states) if e[doc] == started[doc]), default=None)
        if at is not None:
            lost = next((e for e in states[at + 1 :] if e[doc] != started[doc]), None)
            ages.append(kill_t - lost["t"] if lost else 0.0)
    return max(ages)


def start_session(a: argparse.Namespace, work: Path, seed: int, engine: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    log = open(work / "sessions.log", "a")  # noqa: SIM115 (the child writes it)
    args = [sys.executable, str(Path(__file__).resolve()), "session", "--state", str(work / "state")]
    args += ["--journal", str(work / "journal.jsonl"), "--clip", str(a.clip), "--seed", str(seed)]
    args += ["--engine", engine, "--method", a.method, "--edit-ms", str(a.edit_ms)]
    return subprocess.Popen(args, env=env, cwd=REPO, stdout=log, stderr=log)


def gone(pid: int | None, timeout_s: float) -> bool:
    end = time.monotonic() + timeout_s
    while pid is not None and time.monotonic() < end:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.2)
    return pid is None


def quit_cleanly(proc: subprocess.Popen, work: Path, journal: Path) -> list[str]:
    (work / "state" / "quit").touch()
    bad = []
    try:
        proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        bad.append("the session did not quit within 120 s")
    if proc.returncode != 0:
        bad.append(f"the clean quit exited {proc.returncode}")
    left = sorted(p.name for p in (work / "state").glob("autosave-*"))
    if left:
        bad.append(f"a clean quit left autosave files: {left}")
    return bad


def studio_kills(a: argparse.Namespace, work: Path, rng: random.Random) -> int:
    journal = work / "journal.jsonl"
    passed, losses, failures = 0, [], []
    killed: list[dict] = []
    kill_t = 0.0
    for k in range(a.kills + 1):
        mark = len(read_journal(journal))
        proc = start_session(a, work, rng.randrange(1 << 30), a.engine)
        started = wait_for(journal, "started", proc.pid, a.start_timeout, mark, proc)
        if k > 0:
            bad = check_recovery(killed, kill_t, started, a.max_loss)
            loss = loss_s(killed, kill_t, started)
            losses.append(loss)
            docs = ",".join(sorted(started["left"])) or "nothing"
            print(f"kill {k}: recovered {docs}; oldest edit lost {loss:.1f} s old: {'ok' if not bad else bad}")
            passed += not bad
            failures += [f"kill {k}: {b}" for b in bad]
        if k == a.kills:
            bad = quit_cleanly(proc, work, journal)
            print(f"clean quit: {'ok' if not bad else bad}")
            failures += bad
            break
        time.sleep(rng.uniform(a.min_edit, a.max_edit))
        engine_pid = next(
            (
                e["engine_pid"]
                for e in reversed(read_journal(journal))
                if e["event"] == "engine" and e["pid"] == proc.pid
            ),
            None,
        )
        kill_t = time.time()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        killed = [e for e in read_journal(journal)[mark:] if e["pid"] == proc.pid]
        if not gone(engine_pid, 15.0):
            failures.append(f"kill {k + 1}: the solver process {engine_pid} outlived the killed studio by 15 s")
            os.kill(engine_pid, signal.SIGKILL)
    print(
        f"kill-test studio kills={a.kills} passed={passed} max_loss_s={max(losses, default=0):.1f} "
        f"failures={len(failures)} work={work}"
    )
    for f in failures:
        print(f"  {f}")
    return 0 if passed == a.kills and not failures else 1


def engine_kills(a: argparse.Namespace, work: Path, rng: random.Random) -> int:
    journal = work / "journal.jsonl"
    proc = start_session(a, work, rng.randrange(1 << 30), "process")
    started = wait_for(journal, "started", proc.pid, a.start_timeout, 0, proc)
    failures = list(started["problems"])
    passed = 0
    last_kill = time.monotonic() - 60.0
    for k in range(1, a.kills + 1):
        # three deaths within 60 s stop the restarts (by design): at least 31 s apart
        time.sleep(max(0.0, last_kill + 31.0 - time.monotonic()) + rng.uniform(0.5, a.max_edit))
        entries = read_journal(journal)
        pid = next(e["engine_pid"] for e in reversed(entries) if e["event"] == "engine")
        last_kill = time.monotonic()
        os.kill(pid, signal.SIGKILL)
        try:
            restarted = wait_for(journal, "engine", proc.pid, 30.0, len(entries), proc)
            done = wait_for(journal, "engine_ok|engine_bad", proc.pid, a.start_timeout, len(entries), proc)
        except (TimeoutError, RuntimeError) as exc:
            failures.append(f"kill {k}: {exc}")
            print(f"kill {k}: {exc}")
            break
        if done["event"] == "engine_bad":
            failures.append(f"kill {k}: after {done['waited_s']} s the new solver still showed {done['lacks']}")
            print(failures[-1])
            continue
        print(
            f"kill {k}: restarted ({restarted['line']}); the new solver showed the session after {done['waited_s']} s"
        )
        passed += 1
    bad = quit_cleanly(proc, work, journal) if proc.poll() is None else ["the session ended"]
    print(f"clean quit: {'ok' if not bad else bad}")
    failures += bad
    print(f"kill-test engine kills={a.kills} passed={passed} failures={len(failures)} work={work}")
    for f in failures:
        print(f"  {f}")
    return 0 if passed == a.kills and not failures else 1


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("what", choices=("studio", "engine", "session"), help="what is killed (session: internal)")
    p.add_argument("--kills", type=int, default=10)
    p.add_argument("--seed", type=int, default=51)
    p.add_argument("--clip", type=Path, default=REPO / "assets" / "clips" / "example.bvh")
    p.add_argument("--method", default="ik", help="the studio's method (default: ik)")
    p.add_argument("--engine", choices=("process", "thread"), default="process", help="studio kills: the solver")
    p.add_argument("--edit-ms", type=int, default=300, help="one edit every MS milliseconds")
    p.add_argument("--min-edit", type=float, default=2.0, help="seconds of editing before a kill, at least")
    p.add_argument("--max-edit", type=float, default=12.0, help="seconds of editing before a kill, at most")
    p.add_argument("--max-loss", type=float, default=5.0, help="edits older than this at a kill must come back")
    p.add_argument("--start-timeout", type=float, default=300.0, help="seconds a start may take")
    p.add_argument("--work", type=Path, help="folder for the state and journal (default: a new temporary one)")
    p.add_argument("--state", help=argparse.SUPPRESS)
    p.add_argument("--journal", help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.what == "session":
        return session_main(a)
    work = a.work or Path(tempfile.mkdtemp(prefix=f"kill-{a.what}-"))
    (work / "state").mkdir(parents=True, exist_ok=True)
    rng = random.Random(a.seed)
    return studio_kills(a, work, rng) if a.what == "studio" else engine_kills(a, work, rng)


if __name__ == "__main__":
    sys.exit(main())
