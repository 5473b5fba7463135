"""Does averaging the pose bank's prior latent over time steady the body where the bank
gives the prior? On `hdm05/` with preset 4 the bank prior is what makes DragPoser's
jitter twice the predictor prior's (docs/accuracy.md, "Where DragPoser's jitter on other
labs' clips comes from").

    PYTHONPATH=. python research/bank_ema.py A FILE... [--sensors 4] [--max-frames N]

Each frame the bank answers, the prior latent becomes ``z_t = A z_(t-1) + (1 - A) z_bank``
(restarted from ``z_bank`` on the first such frame after one it did not answer);
``A = 0`` is the shipped behaviour. Runs ``dragposer-studio evaluate --method dragposer``
in this process (``--jobs 1``) and prints its table.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))


def averaged(latent, a: float):
    """``PriorSource.latent`` with the bank's latent averaged over time by factor ``a``."""

    def wrapped(self, frame, s, readings):
        z, weight, warnings = latent(self, frame, s, readings)
        if readings is None or z is None:
            self._ema = None
            return z, weight, warnings
        prev = getattr(self, "_ema", None)
        self._ema = z.clone() if prev is None or frame == 0 else a * prev + (1.0 - a) * z
        return self._ema.clone(), weight, warnings

    return wrapped


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a", type=float)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--sensors", default="4")
    ap.add_argument("--max-frames", type=int)
    args = ap.parse_args()
    from engine.cli.main import main as cli
    from engine.methods import dragposer_prior

    dragposer_prior.PriorSource.latent = averaged(dragposer_prior.PriorSource.latent, args.a)
    argv = ["evaluate", *args.files, "--method", "dragposer", "--sensors", args.sensors, "--jobs", "1", "--no-progress"]
    argv += ["--max-frames", str(args.max_frames)] if args.max_frames else []
    return cli(argv) or 0


if __name__ == "__main__":
    sys.exit(main())
