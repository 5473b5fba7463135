"""Soak runs (issue 51, docs/reliability.md): the studio playing a clip on loop, or ``live``
receiving a looping 60 Hz VMC stream, for ``--minutes``, with one line of figures a minute.

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/soak.py studio --minutes 30
    .venv/bin/python scripts/soak.py live --minutes 30

``studio``: the studio window (its solver in its own process, as ``gui`` runs it) opens
``--clip`` and plays it on loop. Each minute: the resident memory (RSS) of the window's
process and of the solver's, view draws and solved frames per second, the lateness of a
10 ms timer on the GUI thread (p50 / p99 / max: how long the window could not answer),
the CPU time per draw (the window's process) and per solve (the solver's), plus what
could grow (Python objects, the undo stack).

``live``: a sender process streams ``--clip``'s simulated trackers as VMC bundles at
``--fps`` (60), looping the clip with the stream time running on; this process receives
and solves them as ``dragposer-studio live`` does (its receiver, method and loop). Each
minute: RSS, packets and solved frames per second, frames skipped, the loop's lateness
(packet arrival to solved pose, p50 / p99 / max; the live loop has no other event
loop), and the CPU time per solve and per optimizer iteration.

Every row also holds the machine's load average and the cores the soak kept busy. The
last lines compare the last minute with the first (scripts/soak_figures.py: RSS and the
CPU time a minute for the same work always; the wall rates and p99 only when the load
the soak did not make stayed about the same) and the exit status says whether the
targets were met;
``--json`` writes every minute and the verdict. Every thread's stack goes to stderr on
a fatal signal, on SIGUSR1, when ``--watchdog-s`` pass without progress, and when the
finished run has not exited within 30 s.
"""

from __future__ import annotations

import argparse
import faulthandler
import gc
import json
import multiprocessing
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's packages, not an installed copy

from scripts.soak_figures import cpu_s, finish, load_avg, per_unit_ms, percentiles, rss_mb  # noqa: E402
from scripts.soak_figures import verdict as verdict  # noqa: E402  (the verdict, for callers of this script)

EXAMPLE = REPO / "assets" / "clips" / "example.bvh"
PROBE_MS = 10
#: Seconds without progress (start-up, the model's load included) before every thread's stack is dumped.
WATCHDOG_S = 300.0
#: Seconds a finished run may take to exit before every thread's stack is dumped.
EXIT_WATCHDOG_S = 30.0


def watchdog(seconds: float) -> None:
    """Dump every thread's stack to stderr if ``seconds`` pass before the next call (and
    every ``seconds`` after), so a run that hangs leaves where it hung in its log."""
    faulthandler.dump_traceback_later(seconds, repeat=True)


def arm_faulthandler(seconds: float) -> None:
    """Stacks of every thread on a fatal signal, on SIGUSR1 and at the :func:`watchdog`."""
    faulthandler.enable(all_threads=True)
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    watchdog(seconds)


def exit_watch() -> None:
    """Before exiting: name what could keep the process alive (threads that are not
    daemons, child processes) and dump the stacks if it is still here in
    :data:`EXIT_WATCHDOG_S`."""
    threads = [t.name for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    children = [p.pid for p in multiprocessing.active_children()]
    if threads or children:
        print(f"soak: at exit, threads still running {threads}, child processes {children}", file=sys.stderr)
    watchdog(EXIT_WATCHDOG_S)


# -- the studio --------------------------------------------------------------------------


def studio(a: argparse.Namespace) -> int:
    from PyQt6.QtCore import QSettings, Qt, QTimer
    from PyQt6.QtWidgets import QApplication

    from app.main_window import MainWindow

    os.environ.setdefault("LP_NUM_THREADS", str(max(1, (os.cpu_count() or 2) - 1)))  # as `gui` does
    app = QApplication(sys.argv[:1])
    folder = Path(a.work or "/tmp") / f"soak-studio-{os.getpid()}"
    folder.mkdir(parents=True, exist_ok=True)
    w = MainWindow(
        method=a.method, engine=a.engine, settings=QSettings(str(folder / "studio.ini"), QSettings.Format.IniFormat)
    )
    if not w.files.open_path(str(a.clip), ask=False):
        raise SystemExit(f"cannot open {a.clip}")
    w.undo.set_clean()
    w.resize(1600, 1000)
    w.show()
    s = w.session
    s.set_playback(loop=True)
    s.play()
    minutes: list[dict[str, Any]] = []
    late: list[float] = []
    probe = QTimer(interval=PROBE_MS)
    probe.setTimerType(Qt.TimerType.PreciseTimer)
    last = {"t": time.perf_counter()}

    def tick() -> None:
        now = time.perf_counter()
        late.append(max(0.0, (now - last["t"]) * 1000.0 - PROBE_MS))
        last["t"] = now

    probe.timeout.connect(tick)
    mark: dict[str, Any] = {}

    def solved() -> int:
        snap = s.latest
        return 0 if snap is None else int(snap.solved)

    def engine_pid() -> int | None:
        process = getattr(w.engine, "_process", None)
        return None if process is None else int(process.pid)

    def marks() -> dict[str, Any]:
        pid = engine_pid()
        return {
            "draws": w.drawing.draws,
            "solved": solved(),
            "engine": w.engine,
            "cpu": cpu_s(),
            "engine_cpu": cpu_s(pid) if pid is not None else 0.0,
        }

    def begin() -> None:
        """Once playback solves (the model's load is not measured)."""
        snap = s.latest
        if snap is None or not snap.playing or snap.solved < 2:
            QTimer.singleShot(200, begin)
            return
        mark.update(t=time.monotonic(), **marks())
        late.clear()
        last["t"] = time.perf_counter()
        probe.start()
        QTimer.singleShot(int(a.minute_s * 1000), minute)

    def minute() -> None:
        now = time.monotonic()
        dt = now - mark["t"]
        restarted = w.engine is not mark["engine"]  # the solver's counters began again
        pid = engine_pid()
        draws = w.drawing.draws - mark["draws"]
        solves = solved() - (0 if restarted else mark["solved"])
        cpu = cpu_s() - mark["cpu"]
        engine_cpu = (cpu_s(pid) if pid is not None else 0.0) - (0.0 if restarted else mark["engine_cpu"])
        row = {
            "minute": len(minutes) + 1,
            "rss_mb": round(rss_mb(), 1),
            "engine_rss_mb": round(rss_mb(pid), 1) if pid is not None else None,
            "draws_per_s": round(draws / dt, 2),
            "solved_per_s": round(solves / dt, 2),
            "event_loop_ms": percentiles(late),
            "cpu_s": round(cpu, 3),
            "draws": draws,
            "engine_cpu_s": round(engine_cpu, 3),
            "solves": solves,
            "cpu_ms_per_draw": per_unit_ms(cpu, draws),
            "engine_cpu_ms_per_solve": per_unit_ms(engine_cpu, solves),
            "own_cores": round((cpu + engine_cpu) / dt, 3),
            "load_avg": load_avg(),
            "python_objects": len(gc.get_objects()),
            "undo_steps": w.undo.history.count(),
            "playing": bool(s.playing),
            "engine_restarted": restarted,
        }
        minutes.append(row)
        print(json.dumps(row), flush=True)
        mark.update(t=now, **marks())
        late.clear()
        watchdog(a.watchdog_s)
        if len(minutes) >= a.minutes:
            probe.stop()
            w.close()
            app.quit()
        else:
            QTimer.singleShot(int(a.minute_s * 1000), minute)

    QTimer.singleShot(300, begin)
    app.exec()
    rates, cpu = ("draws_per_s", "solved_per_s"), (("cpu_s", ("draws",)), ("engine_cpu_s", ("solves",)))
    return finish("studio", minutes, rates, "event_loop_ms", cpu, a.json)


# -- live --------------------------------------------------------------------------------


def send(a: argparse.Namespace) -> int:
    """The looping sender (a process of its own): the clip's trackers as VMC bundles at
    ``--fps``, the stream time running on across loops, until ``--seconds`` passed."""
    from engine.motion.retarget import load_motion
    from engine.tracker_io.sender import plan_stream
    from engine.tracker_io.vmc import encode_packets

    plan = plan_stream(load_motion(a.clip), a.sensors, fps=a.fps)
    period = len(plan) / a.fps
    host, port = a.to.rsplit(":", 1)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    start = time.perf_counter()
    i = 0
    while i / a.fps < a.seconds:
        wait = start + i / a.fps - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
        k = i % len(plan)
        t = float(plan.times[k]) + (i // len(plan)) * period
        for dgram in encode_packets(t, plan.frame(k)):
            sock.sendto(dgram, (host, int(port)))
        i += 1
        if i % max(1, int(a.fps)) == 0:  # a second of stream sent: the sender is alive
            watchdog(a.watchdog_s)
    sock.close()
    return 0


def live(a: argparse.Namespace) -> int:
    from engine.cli.live import _check, _warm_up
    from engine.cli.main import build_parser
    from engine.cli.method_options import build_method
    from engine.cli.tracker_options import default_skeleton, load_reference
    from engine.tracker_io.live import LiveRun, default_budget_ms
    from engine.tracker_io.receiver import VMCReceiver
    from engine.tracker_io.trackers import TrackerMapping

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:  # a free port
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    # the options `dragposer-studio live` would get
    args = build_parser().parse_args(["live", "--listen", f"127.0.0.1:{port}", "--method", a.method, *a.live_args])
    _check(args)
    reference = load_reference(args)
    method = build_method(args)
    skeleton = default_skeleton(reference)
    _warm_up(method, skeleton, args.fps)
    receiver = VMCReceiver("127.0.0.1", port, TrackerMapping.parse(args.map), args.convention, args.timeout, None)
    budget = default_budget_ms(args.fps) if args.frame_budget is None else args.frame_budget
    run = LiveRun(
        receiver, method, skeleton, args.fps, 0.0, "auto", budget if method.takes_deadline else 0.0, keep_frames=False
    )
    seconds = a.minutes * a.minute_s
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")])}
    sender = subprocess.Popen(
        [
            sys.executable,
            str(Path(__file__).resolve()),
            "send",
            "--to",
            f"127.0.0.1:{port}",
            "--clip",
            str(a.clip),
            "--fps",
            str(args.fps),
            "--seconds",
            str(seconds + 30),
            "--watchdog-s",
            str(a.watchdog_s),
        ],
        env=env,
        cwd=REPO,
    )
    minutes: list[dict[str, Any]] = []
    mark: dict[str, Any] = {}
    late: list[float] = []  # this minute's latencies, ms
    iterations = [0]  # this minute's optimizer iterations

    def on_frame(result: Any) -> None:
        now = time.monotonic()
        late.append(result.figures.latency_ms[-1])
        iterations[0] += int(result.figures.iterations[-1])
        if not mark:
            mark.update(
                t=now,
                solved=result.frames_solved,
                received=result.frames_received,
                skipped=result.frames_skipped,
                packets=receiver.snapshot_stats().packets,
                cpu=cpu_s(),
                sender_cpu=cpu_s(sender.pid),
            )
            late.clear()
            iterations[0] = 0
            return
        if now - mark["t"] < a.minute_s:
            return
        dt = now - mark["t"]
        packets = receiver.snapshot_stats().packets
        solves = result.frames_solved - mark["solved"]
        cpu, sender_cpu = cpu_s(), cpu_s(sender.pid)
        row = {
            "minute": len(minutes) + 1,
            "rss_mb": round(rss_mb(), 1),
            "packets_per_s": round((packets - mark["packets"]) / dt, 2),
            "solved_per_s": round(solves / dt, 2),
            "frames_received": result.frames_received - mark["received"],
            "frames_skipped": result.frames_skipped - mark["skipped"],
            "latency_ms": percentiles(late),
            "cpu_s": round(cpu - mark["cpu"], 3),
            "solves": solves,
            "iterations": iterations[0],
            "cpu_ms_per_solve": per_unit_ms(cpu - mark["cpu"], solves),
            "iterations_per_solve": round(iterations[0] / solves, 2) if solves else None,
            "cpu_ms_per_iteration": per_unit_ms(cpu - mark["cpu"], iterations[0]),
            "own_cores": round((cpu - mark["cpu"] + sender_cpu - mark["sender_cpu"]) / dt, 3),
            "load_avg": load_avg(),
            "python_objects": len(gc.get_objects()),
            "kept_results": len(result.results),
        }
        minutes.append(row)
        print(json.dumps(row), flush=True)
        mark.update(
            t=now,
            solved=result.frames_solved,
            received=result.frames_received,
            skipped=result.frames_skipped,
            packets=packets,
            cpu=cpu,
            sender_cpu=sender_cpu,
        )
        late.clear()
        iterations[0] = 0
        watchdog(a.watchdog_s)
        if len(minutes) >= a.minutes:
            run.stop_event.set()

    print(f"soak live: receiving on 127.0.0.1:{port} (method {a.method}) for {a.minutes} minutes", flush=True)
    try:
        with receiver:
            run.run(seconds + 60, on_frame=on_frame)
    finally:
        sender.terminate()
        sender.wait()
    cpu = (("cpu_s", ("solves", "iterations")),)  # the receiver's part is in the fit's constant
    return finish("live", minutes, ("packets_per_s", "solved_per_s"), "latency_ms", cpu, a.json)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="what", required=True)
    for name in ("studio", "live"):
        q = sub.add_parser(name)
        q.add_argument("--minutes", type=int, default=30, help="how long (default: 30, the issue's target)")
        q.add_argument("--clip", type=Path, default=EXAMPLE, help="the clip (default: the bundled example)")
        q.add_argument("--json", type=Path, help="write every minute and the verdict here")
        q.add_argument("--minute-s", type=float, default=60.0, help=argparse.SUPPRESS)  # shorter in the tests
    sub.choices["studio"].add_argument("--method", default="dragposer")
    sub.choices["studio"].add_argument("--engine", choices=("process", "thread"), default="process")
    sub.choices["studio"].add_argument("--work", help="folder for the window's settings (default: /tmp)")
    sub.choices["live"].add_argument("--method", default="dragposer")
    sub.choices["live"].add_argument("live_args", nargs="*", help="more `live` options, after --")
    q = sub.add_parser("send")
    q.add_argument("--to", required=True)
    q.add_argument("--clip", type=Path, required=True)
    q.add_argument("--fps", type=float, default=60.0)
    q.add_argument("--sensors", default="6")
    q.add_argument("--seconds", type=float, required=True)
    for q in sub.choices.values():
        q.add_argument(
            "--watchdog-s",
            type=float,
            default=WATCHDOG_S,
            help=f"dump every thread's stack to stderr when the run makes no progress (a minute's row;"
            f" the sender: a second of stream) for this long, seconds (default: {WATCHDOG_S:.0f})",
        )
    a = p.parse_args(argv)
    arm_faulthandler(a.watchdog_s)
    return {"studio": studio, "live": live, "send": send}[a.what](a)


if __name__ == "__main__":
    status = main()
    exit_watch()
    sys.exit(status)
