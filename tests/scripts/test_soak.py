"""The soak runs' verdict and their stack dumps (scripts/soak.py, docs/reliability.md)."""

from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

from scripts.soak import verdict

REPO = Path(__file__).resolve().parents[2]
RATES, LATENESS, CPU = ("packets_per_s", "solved_per_s"), "latency_ms", ("cpu_ms_per_solve",)


def minute(
    rate: float = 60.0, p99: float = 12.0, cpu_ms: float = 5.0, load: float = 1.3, own: float = 0.3, rss: float = 560.0
) -> dict:
    """A live soak's minute row with the figures the verdict reads."""
    return {
        "rss_mb": rss,
        "packets_per_s": 60.0,
        "solved_per_s": rate,
        "latency_ms": {"p50": p99 / 2, "p99": p99, "max": 2 * p99},
        "cpu_ms_per_solve": cpu_ms,
        "load_avg": load,
        "own_cores": own,
    }


def test_wall_rates_are_not_judged_when_the_other_load_changed() -> None:
    """A shared machine: other work (1.0 -> 2.2 cores) slows the soak's wall figures by
    over 10 % while its CPU time per solve holds: within the targets, the wall figures
    printed as not judged beside the loads."""
    rows = [minute(), minute(rate=51.0, p99=30.0, cpu_ms=5.2, load=2.5)]
    ok, lines = verdict(rows, RATES, LATENESS)
    assert ok, lines
    ok, lines = verdict(rows, RATES, LATENESS, CPU)
    assert ok, lines
    assert any("other load 1.00 -> 2.20" in line for line in lines), lines
    assert any(line.startswith("solved_per_s: 60.00 -> 51.00") and "not judged" in line for line in lines), lines
    assert any(line.startswith("latency_ms p99") and "not judged" in line for line in lines), lines


def test_cpu_time_per_solve_is_judged_whatever_the_load() -> None:
    """The soak's own slowdown shows as more CPU time per solve: outside the targets even
    when the other load excuses the wall rates."""
    ok, lines = verdict([minute(), minute(rate=51.0, cpu_ms=5.8, load=2.5)], RATES, LATENESS, CPU)
    assert not ok
    assert any(line.startswith("cpu_ms_per_solve: 5.00 -> 5.80 (+16.0 %") and "OVER" in line for line in lines)


def test_wall_rates_are_judged_when_the_other_load_held() -> None:
    """With the same other load in both minutes a slower wall rate or a later p99 is the soak's."""
    ok, lines = verdict([minute(), minute(rate=51.0, load=1.4, own=0.35)], RATES, LATENESS, CPU)
    assert not ok
    assert any(line.startswith("solved_per_s") and "OFF" in line for line in lines), lines
    ok, lines = verdict([minute(), minute(p99=14.0)], RATES, LATENESS, CPU)
    assert not ok
    assert any(line.startswith("latency_ms p99") and "OFF" in line for line in lines), lines
    assert verdict([minute(), minute(rate=57.0, p99=12.5, cpu_ms=5.3)], RATES, LATENESS, CPU)[0]


def test_rss_growth_is_judged_whatever_the_load() -> None:
    ok, lines = verdict([minute(), minute(rss=560.0 * 1.06, load=2.5)], RATES, LATENESS, CPU)
    assert not ok
    assert any(line.startswith("rss_mb") and "OVER" in line for line in lines), lines


def test_a_stalled_sender_dumps_every_thread_stack(tmp_path: Path) -> None:
    """The watchdog: a run that makes no progress for --watchdog-s leaves its stacks in the log."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        port = sink.getsockname()[1]
        run = subprocess.run(
            [
                sys.executable,
                str(REPO / "scripts" / "soak.py"),
                "send",
                "--to",
                f"127.0.0.1:{port}",
                "--clip",
                str(REPO / "assets" / "clips" / "example.bvh"),
                "--seconds",
                "2.5",
                "--fps",
                "0.5",  # one bundle, then a wait past the watchdog's 0.3 s
                "--watchdog-s",
                "0.3",
            ],
            capture_output=True,
            text=True,
            timeout=120,
            cwd=tmp_path,
        )
    assert run.returncode == 0, run.stderr
    assert "Timeout (0:00:00.300000)!" in run.stderr, run.stderr
    assert "most recent call first" in run.stderr and ", line " in run.stderr and " in send" in run.stderr, run.stderr
