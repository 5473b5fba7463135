"""Memory over a long ``reconstruct``: a synthetic clip of N frames (the bundled clip
repeated, each repeat continuing where the last ended), reconstructed by the real CLI in
a subprocess whose resident memory is read from /proc at every 500th frame (the frame
count comes from the progress bar).

    PYTHONPATH=. python research/memory_long_clip.py [--frames 10000] [--sensors 6] [--iterations N]

(``--iterations`` is passed to ``reconstruct``: fewer make a long run affordable on a busy
machine while the same code paths and per-frame records are exercised.)

Prints RSS (MiB) against frames and the growth after the first 1,000 frames.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def long_clip(frames: int, path: Path) -> None:
    from engine.motion.bvh import save_motion_bvh
    from engine.motion.clip import Motion
    from engine.motion.retarget import load_motion

    m = load_motion(REPO / "assets" / "clips" / "example.bvh")
    reps = -(-frames // len(m))
    local = np.concatenate([m.local_rot] * reps)[:frames]
    roots, shift = [], np.zeros(3)
    for _ in range(reps):
        roots.append(m.root_pos + shift)
        shift = shift + (m.root_pos[-1] - m.root_pos[0]) * np.array([1.0, 1.0, 0.0])
    save_motion_bvh(path, Motion(local, np.concatenate(roots)[:frames], m.skeleton, m.fps, "long"))


def rss_mb(pid: int) -> float:
    """Resident memory of ``pid`` in MiB; NaN once the process has exited (the last
    progress update can arrive after that)."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError:
        return float("nan")
    for line in lines:
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=10000)
    ap.add_argument("--sensors", default="6")
    ap.add_argument("--iterations", type=int, help="optimizer iterations per frame (reconstruct's default: 10)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        clip = Path(tmp) / "long.bvh"
        long_clip(a.frames, clip)
        cmd = [
            sys.executable,
            "-m",
            "engine.cli.main",
            "reconstruct",
            str(clip),
            "--out",
            str(Path(tmp) / "out.bvh"),
            "--sensors",
            a.sensors,
        ] + (["--iterations", str(a.iterations)] if a.iterations else [])
        env = {**os.environ, "PYTHONPATH": str(REPO), "TQDM_MININTERVAL": "0"}
        proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.PIPE, env=env, text=True, bufsize=1)
        samples: dict[int, float] = {}
        buf, step = "", 500
        assert proc.stderr is not None
        while True:
            ch = proc.stderr.read(256)
            if not ch:
                break
            buf = (buf + ch)[-512:]
            found = re.findall(r"(\d+)/(\d+) \[", buf)
            if found:
                done = int(found[-1][0])
                mark = done // step * step
                if mark and mark not in samples:
                    samples[mark] = rss_mb(proc.pid)
                    print(f"frame {mark:>6d}  rss {samples[mark]:8.1f} MiB", flush=True)
        proc.wait()
        print(proc.stdout.read() if proc.stdout else "")
    valid = {k: v for k, v in samples.items() if np.isfinite(v)}  # a process that had exited reads NaN
    base = valid.get(1000)
    if base and valid:
        last = valid[max(valid)]
        print(f"growth after frame 1000: {100.0 * (last - base) / base:+.2f} % ({base:.1f} -> {last:.1f} MiB)")
    return proc.returncode


if __name__ == "__main__":
    raise SystemExit(main())
