"""The soak runs' figures (scripts/soak.py, docs/reliability.md) and their verdict.

A minute's row holds the wall rates (draws, packets or solves a second) and the lateness
p99, which follow whatever else the machine runs, beside figures that do not: the
resident memory, and the CPU seconds the soak's processes spent in the minute with the
work they did (draws, solves, optimizer iterations; per unit too, for reading). Each
row also holds the machine's 1-minute load average (``load_avg``) and the cores the
soak's own processes kept busy (``own_cores``), so the load the soak did not make can
be told apart.

The verdict compares the last minute with the first against the issue's targets: RSS
growth at most 5 % and, always, at most 10 % more CPU time a minute for the same work
(:func:`cpu_drift`, fitted over every minute); the wall rates within 10 % and the p99
at most 10 % later only when the other load was about the same in both minutes (within
:data:`OTHER_LOAD_CHANGE`). When it was not, the wall figures are printed beside the
two loads and marked *not judged*: on a shared machine they measure the other work,
not the soak.
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
#: Minutes the CPU time's fit needs (a constant, the units of work and the trend).
MIN_FIT_MINUTES = 6
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


def cpu_drift(minutes: list[dict[str, Any]], key: str, units: tuple[str, ...]) -> float | None:
    """How much more CPU time a minute took at the end of the run than at its start for
    the same work: a least-squares fit of each minute's ``key`` (CPU seconds) to a
    constant, the minute's ``units`` of work (counts) and the minute's index; the index's
    share over the run, as a fraction of the mean minute's CPU time. None with fewer
    than :data:`MIN_FIT_MINUTES` minutes holding the figures.

    The work a minute does varies on a shared machine (frames skipped, optimizer
    iterations cut short by a deadline) and so does the CPU time per unit of work, by
    the constant part spread over fewer units; the fit takes both out, and a cost that
    grows through the run is left in the index's coefficient.
    """
    rows = [m for m in minutes if m.get(key) is not None and all(m.get(u) is not None for u in units)]
    if len(rows) < MIN_FIT_MINUTES:
        return None
    y = np.array([m[key] for m in rows], float)
    index = np.array([m["minute"] for m in rows], float)
    design = np.column_stack([np.ones(len(rows)), *([m[u] for m in rows] for u in units), index])
    coef = np.linalg.lstsq(design, y, rcond=None)[0]
    return float(coef[-1] * (index[-1] - index[0]) / y.mean()) if y.mean() > 0 else None


def verdict(
    minutes: list[dict[str, Any]],
    rates: tuple[str, ...],
    lateness: str,
    cpu: tuple[tuple[str, tuple[str, ...]], ...] = (),
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
    cpu : tuple of (str, tuple of str)
        Keys of a process's CPU seconds in the minute, each with the keys of the units of
        work it did in the minute (judged by :func:`cpu_drift`).
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
    for key, units in cpu:
        drift = cpu_drift(minutes, key, units)
        if drift is None:
            lines.append(f"{key}: fewer than {MIN_FIT_MINUTES} minutes with the figures, not judged")
            continue
        good = drift <= RATE_CHANGE
        ok &= good
        lines.append(
            f"{key} for the same work ({', '.join(units)}): {100 * drift:+.1f} % from the first minute to the last"
            f" (target <= +10 %) {'ok' if good else 'OVER'}"
        )
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
    kind: str,
    minutes: list[dict],
    rates: tuple[str, ...],
    lateness: str,
    cpu: tuple[tuple[str, tuple[str, ...]], ...],
    out: Path | None,
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
