"""Soak runs (issue 51, docs/reliability.md): the studio playing a clip on loop, or ``live``
receiving a looping 60 Hz VMC stream, for ``--minutes``, with one line of figures a minute.

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python scripts/soak.py studio --minutes 30
    .venv/bin/python scripts/soak.py live --minutes 30

``studio``: the studio window (its solver in its own process, as ``gui`` runs it) opens
``--clip`` and plays it on loop. Each minute: the resident memory (RSS) of the window's
process and of the solver's, view draws and solved frames per second, and the lateness
of a 10 ms timer on the GUI thread (p50 / p99 / max: how long the window could not
answer), plus what could grow (Python objects, the undo stack).

``live``: a sender process streams ``--clip``'s simulated trackers as VMC bundles at
``--fps`` (60), looping the clip with the stream time running on; this process receives
and solves them as ``dragposer-studio live`` does (its receiver, method and loop). Each
minute: RSS, packets and solved frames per second, frames skipped, and the loop's
lateness: packet arrival to solved pose (p50 / p99 / max), the live loop having no
other event loop.

The last lines compare the last minute with the first against the issue's targets (RSS
growth at most 5 %, rates and p99 within 10 %) and the exit status says whether they
were met; ``--json`` writes every minute and the verdict. On a busy machine the rates
and the lateness follow the other load: read them from an idle machine.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # this checkout's packages, not an installed copy
EXAMPLE = REPO / "assets" / "clips" / "example.bvh"
PROBE_MS = 10
#: The issue's targets: RSS growth at most 5 %, rates and p99 within 10 % of the first minute.
RSS_GROWTH, RATE_CHANGE = 0.05, 0.10


def rss_mb(pid: int | None = None) -> float:
    """Resident memory of process ``pid`` (this one by default), MiB; 0 when it is gone."""
    try:
        status = Path(f"/proc/{pid or 'self'}/status").read_text()
    except OSError:
        return 0.0
    kb = next(line.split()[1] for line in status.splitlines() if line.startswith("VmRSS:"))
    return int(kb) / 1024.0


def percentiles(values: list[float]) -> dict[str, float]:
    a = np.asarray(values or [0.0], float)
    return {
        "p50": round(float(np.percentile(a, 50)), 2),
        "p99": round(float(np.percentile(a, 99)), 2),
        "max": round(float(a.max()), 2),
    }


def verdict(minutes: list[dict[str, Any]], rates: tuple[str, ...], lateness: str) -> tuple[bool, list[str]]:
    """Whether the last minute is within the targets of the first; one line per figure."""
    if len(minutes) < 2:
        return True, ["fewer than two minutes: nothing to compare"]
    first, last = minutes[0], minutes[-1]
    lines, ok = [], True
    for key in ("rss_mb", "engine_rss_mb"):
        if first.get(key):
            growth = last[key] / first[key] - 1.0
            good = growth <= RSS_GROWTH
            ok &= good
            lines.append(
                f"{key}: {first[key]:.0f} -> {last[key]:.0f} MiB ({100 * growth:+.1f} %, target <= +5 %)"
                f" {'ok' if good else 'OVER'}"
            )
    for key in (*rates, lateness):
        a = first[key]["p99"] if key == lateness else first[key]
        b = last[key]["p99"] if key == lateness else last[key]
        change = (b / a - 1.0) if a else 0.0
        good = abs(change) <= RATE_CHANGE if key != lateness else change <= RATE_CHANGE
        ok &= good
        name = f"{key} p99" if key == lateness else key
        lines.append(
            f"{name}: {a:.2f} -> {b:.2f} ({100 * change:+.1f} %, target within 10 %) {'ok' if good else 'OFF'}"
        )
    return ok, lines


def finish(kind: str, minutes: list[dict], rates: tuple[str, ...], lateness: str, out: Path | None) -> int:
    ok, lines = verdict(minutes, rates, lateness)
    print(f"soak {kind}: {len(minutes)} minutes, {'within' if ok else 'NOT within'} the targets")
    for line in lines:
        print(f"  {line}")
    if out is not None:
        tmp = out.with_name(out.name + ".tmp")
        tmp.write_text(json.dumps({"kind": kind, "minutes": minutes, "ok": ok, "verdict": lines}, indent=1) + "\n")
        tmp.replace(out)
    return 0 if ok else 1


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

    def begin() -> None:
        """Once playback solves (the model's load is not measured)."""
        snap = s.latest
        if snap is None or not snap.playing or snap.solved < 2:
            QTimer.singleShot(200, begin)
            return
        mark.update(t=time.monotonic(), draws=w.drawing.draws, solved=solved(), engine=w.engine)
        late.clear()
        last["t"] = time.perf_counter()
        probe.start()
        QTimer.singleShot(int(a.minute_s * 1000), minute)

    def minute() -> None:
        now = time.monotonic()
        dt = now - mark["t"]
        restarted = w.engine is not mark["engine"]  # the solver's counters began again
        process = getattr(w.engine, "_process", None)
        row = {
            "minute": len(minutes) + 1,
            "rss_mb": round(rss_mb(), 1),
            "engine_rss_mb": round(rss_mb(process.pid), 1) if process is not None else None,
            "draws_per_s": round((w.drawing.draws - mark["draws"]) / dt, 2),
            "solved_per_s": round((solved() - (0 if restarted else mark["solved"])) / dt, 2),
            "event_loop_ms": percentiles(late),
            "python_objects": len(gc.get_objects()),
            "undo_steps": w.undo.history.count(),
            "playing": bool(s.playing),
            "engine_restarted": restarted,
        }
        minutes.append(row)
        print(json.dumps(row), flush=True)
        mark.update(t=now, draws=w.drawing.draws, solved=solved(), engine=w.engine)
        late.clear()
        if len(minutes) >= a.minutes:
            probe.stop()
            w.close()
            app.quit()
        else:
            QTimer.singleShot(int(a.minute_s * 1000), minute)

    QTimer.singleShot(300, begin)
    app.exec()
    return finish("studio", minutes, ("draws_per_s", "solved_per_s"), "event_loop_ms", a.json)


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
        ],
        env=env,
        cwd=REPO,
    )
    minutes: list[dict[str, Any]] = []
    mark: dict[str, Any] = {}
    late: list[float] = []  # this minute's latencies, ms

    def on_frame(result: Any) -> None:
        now = time.monotonic()
        late.append(result.figures.latency_ms[-1])
        if not mark:
            mark.update(
                t=now,
                solved=result.frames_solved,
                received=result.frames_received,
                skipped=result.frames_skipped,
                packets=receiver.snapshot_stats().packets,
            )
            late.clear()
            return
        if now - mark["t"] < a.minute_s:
            return
        dt = now - mark["t"]
        packets = receiver.snapshot_stats().packets
        row = {
            "minute": len(minutes) + 1,
            "rss_mb": round(rss_mb(), 1),
            "packets_per_s": round((packets - mark["packets"]) / dt, 2),
            "solved_per_s": round((result.frames_solved - mark["solved"]) / dt, 2),
            "frames_received": result.frames_received - mark["received"],
            "frames_skipped": result.frames_skipped - mark["skipped"],
            "latency_ms": percentiles(late),
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
        )
        late.clear()
        if len(minutes) >= a.minutes:
            run.stop_event.set()

    print(f"soak live: receiving on 127.0.0.1:{port} (method {a.method}) for {a.minutes} minutes", flush=True)
    try:
        with receiver:
            run.run(seconds + 60, on_frame=on_frame)
    finally:
        sender.terminate()
        sender.wait()
    return finish("live", minutes, ("packets_per_s", "solved_per_s"), "latency_ms", a.json)


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
    a = p.parse_args(argv)
    return {"studio": studio, "live": live, "send": send}[a.what](a)


if __name__ == "__main__":
    sys.exit(main())
