"""The soak runs' figures (scripts/soak.py, docs/reliability.md) and their verdict.

A minute's row holds the wall rates (draws, packets or solves a second) and the lateness
p99, which follow whatever else the machine runs, beside figures that other load does
not move: the resident memory, and the CPU time the soak's processes spent per unit of
work (per draw, per solve, per optimizer iteration). Each row also holds the machine's
1-minute load average (``load_avg``) and the cores the soak's own processes kept busy
(``own_cores``), so the load the soak did not make can be told apart.

The verdict compares the last minute with the first against the issue's targets: RSS
growth at most 5 % and CPU time per unit of work at most 10 % more, always; the wall
rates within 10 % and the p99 at most 10 % later only when the other load was about the
same in both minutes (within :data:`OTHER_LOAD_CHANGE`). When it was not, the wall
figures are printed beside the two loads and marked *not judged*: on a shared machine
they measure the other work, not the soak.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

#: The issue's targets: RSS growth at most 5 %, rates and p99 within 10 % of the first minute.
RSS_GROWTH, RATE_CHANGE = 0.05, 0.10
#: Change of the load the soak did not make (run-queue entries, i.e. busy cores on this
#: machine) above which its wall rates and lateness are not comparable between two minutes.
OTHER_LOAD_CHANGE = 0.5
_TICK_S = 1.0 / os.sysconf("SC_CLK_TCK")


def rss_mb(pid: int | None = None) -> float:
    """Resident memory of process ``pid`` (this one by default), MiB; 0 when it is gone."""
    try:
        status = Path(f"/proc/{pid or 'self'}/status").read_text()
    except OSError:
        return 0.0
    kb = next(line.split()[1] for line in status.splitlines() if line.startswith("VmRSS:"))
    return int(kb) / 1024.0


def cpu_s(pid: int | None = None) -> float:
    """CPU time (user + system, all threads) process ``pid`` has used, seconds; this
    process by default; 0 when it is gone."""
    if pid is None:
        return time.process_time()
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return 0.0
    fields = stat[stat.rindex(")") + 2 :].split()  # after the command name, which may hold spaces
    return (int(fields[11]) + int(fields[12])) * _TICK_S  # utime, stime: fields 14 and 15


def load_avg() -> float:
    """The machine's 1-minute load average (runnable tasks)."""
    return round(os.getloadavg()[0], 2)


def per_unit_ms(cpu_seconds: float, units: float) -> float | None:
    """CPU milliseconds per unit of work; None when no work was done."""
    return round(1000.0 * cpu_seconds / units, 3) if units > 0 else None


def percentiles(values: list[float]) -> dict[str, float]:
    """p50, p99 and maximum of ``values`` (0 when empty), rounded to 0.01."""
    a = np.asarray(values or [0.0], float)
    return {
        "p50": round(float(np.percentile(a, 50)), 2),
        "p99": round(float(np.percentile(a, 99)), 2),
        "max": round(float(a.max()), 2),
    }


def other_load(row: dict[str, Any]) -> float | None:
    """The load the soak did not make in a minute's row: its load average less the cores
    the soak's processes kept busy; None when the row lacks either."""
    if row.get("load_avg") is None or row.get("own_cores") is None:
        return None
    return max(0.0, float(row["load_avg"]) - float(row["own_cores"]))


def _change(a: float, b: float) -> float:
    return (b / a - 1.0) if a else 0.0


def verdict(
    minutes: list[dict[str, Any]], rates: tuple[str, ...], lateness: str, cpu: tuple[str, ...] = ()
) -> tuple[bool, list[str]]:
    """Whether the last minute is within the targets of the first; one line per figure.

    Parameters
    ----------
    minutes : list of dict
        The minutes' rows, first to last.
    rates : tuple of str
        Keys of the wall rates (per second).
    lateness : str
        Key of the lateness percentiles (ms; its ``p99`` is judged).
    cpu : tuple of str
        Keys of the CPU milliseconds per unit of work.
    """
    if len(minutes) < 2:
        return True, ["fewer than two minutes: nothing to compare"]
    first, last = minutes[0], minutes[-1]
    lines, ok = [], True
    for key in ("rss_mb", "engine_rss_mb"):
        if first.get(key):
            growth = _change(first[key], last[key])
            good = growth <= RSS_GROWTH
            ok &= good
            lines.append(
                f"{key}: {first[key]:.0f} -> {last[key]:.0f} MiB ({100 * growth:+.1f} %, target <= +5 %)"
                f" {'ok' if good else 'OVER'}"
            )
    for key in cpu:
        a, b = first.get(key), last.get(key)
        if not a or b is None:
            lines.append(f"{key}: no figure in the first or last minute, not judged")
            continue
        change = _change(a, b)
        good = change <= RATE_CHANGE
        ok &= good
        lines.append(f"{key}: {a:.2f} -> {b:.2f} ({100 * change:+.1f} %, target <= +10 %) {'ok' if good else 'OVER'}")
    load_a, load_b = other_load(first), other_load(last)
    confounded = load_a is not None and load_b is not None and abs(load_b - load_a) > OTHER_LOAD_CHANGE
    if load_a is not None and load_b is not None:
        lines.append(
            f"load average {first['load_avg']:.2f} -> {last['load_avg']:.2f}, the soak's own"
            f" {first['own_cores']:.2f} -> {last['own_cores']:.2f} cores, other load {load_a:.2f} -> {load_b:.2f}"
            + (f" (changed by more than {OTHER_LOAD_CHANGE}: wall figures not judged)" if confounded else "")
        )
    for key in (*rates, lateness):
        a = first[key]["p99"] if key == lateness else first[key]
        b = last[key]["p99"] if key == lateness else last[key]
        change = _change(a, b)
        good = abs(change) <= RATE_CHANGE if key != lateness else change <= RATE_CHANGE
        name = f"{key} p99" if key == lateness else key
        if confounded:
            mark = "not judged"
        else:
            ok &= good
            mark = "ok" if good else "OFF"
        lines.append(f"{name}: {a:.2f} -> {b:.2f} ({100 * change:+.1f} %, target within 10 %) {mark}")
    return ok, lines


def finish(
    kind: str, minutes: list[dict], rates: tuple[str, ...], lateness: str, cpu: tuple[str, ...], out: Path | None
) -> int:
    """Print the verdict (and write every minute and it to ``out``); the exit status."""
    ok, lines = verdict(minutes, rates, lateness, cpu)
    print(f"soak {kind}: {len(minutes)} minutes, {'within' if ok else 'NOT within'} the targets")
    for line in lines:
        print(f"  {line}")
    if out is not None:
        tmp = out.with_name(out.name + ".tmp")
        tmp.write_text(json.dumps({"kind": kind, "minutes": minutes, "ok": ok, "verdict": lines}, indent=1) + "\n")
        tmp.replace(out)
    return 0 if ok else 1
