"""``dragposer-studio train vae|predictor|sparseposer|rpm|stance|heading|tracker-net``: train the models on prepared data.

Settings come from the dataclass defaults, then ``--config FILE.toml``, then
``--set key=value`` (repeatable), then the common flags. Runs unchanged under
``torchrun --nproc_per_node=N`` (DistributedDataParallel; gloo on CPU, nccl on CUDA).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def _common(p: argparse.ArgumentParser, out_default: str) -> None:
    p.add_argument("--data", type=Path, default=Path("prepared"), help="output of `data prepare` (default: prepared)")
    p.add_argument("--out", type=Path, default=Path(out_default), help=f"run folder (default: {out_default})")
    p.add_argument("--config", type=Path, help="TOML file with settings")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override one setting")
    p.add_argument("--epochs", type=int, help="maximum epochs")
    p.add_argument("--batch-size", type=int, dest="batch_size", help="batch size per process")
    p.add_argument("--lr", type=float, help="peak learning rate")
    p.add_argument("--minutes", type=float, help="wall-clock budget; stops cleanly after the epoch that reaches it")
    p.add_argument("--seed", type=int, help="random seed")
    p.add_argument("--resume", action="store_true", help="continue from OUT/last.pt")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument(
        "--device",
        choices=("auto", "cpu", "cuda"),
        default="auto",
        help="where the VAE and the predictor train (default auto: a CUDA device when torch sees one, "
        "else the CPU); SparsePoser and RPM train on the CPU",
    )


def _perceptron_parser(
    tsub: argparse._SubParsersAction, name: str, help: str, description: str, hidden: int
) -> argparse.ArgumentParser:
    """The subcommand of one small perceptron (engine/training/perceptron.py) and its options."""
    p = tsub.add_parser(name, help=help, description=description)
    p.add_argument("--data", type=Path, default=Path("prepared"), help="output of `data prepare` (default: prepared)")
    p.add_argument("--out", type=Path, default=Path(f"runs/{name}.npz"), help=f"model file (default: runs/{name}.npz)")
    p.add_argument("--hidden", type=int, default=hidden, help=f"width of the two hidden layers (default {hidden})")
    p.add_argument("--epochs", type=int, default=10, help="passes over the samples (default 10)")
    p.add_argument("--seed", type=int, default=0, help="random seed")
    return p


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "train",
        help="train the pose VAE, the temporal predictor, SparsePoser, RPM, the stance classifier, the heading "
        "network or the tracker networks",
    )
    tsub = p.add_subparsers(dest="train_command", metavar="MODEL")
    v = tsub.add_parser("vae", help="train the pose VAE", description=__doc__)
    _common(v, "runs/vae")
    v.set_defaults(func=_train_vae)
    q = tsub.add_parser("predictor", help="train the temporal predictor", description=__doc__)
    _common(q, "runs/predictor")
    q.add_argument("--vae", type=Path, default=Path("runs/vae/vae.pt"), help="trained VAE weights")
    q.set_defaults(func=_train_predictor)
    s = tsub.add_parser("sparseposer", help="train SparsePoser (generator + learned IK, preset 6)", description=__doc__)
    _common(s, "runs/sparseposer")
    s.set_defaults(func=_train_sparseposer)
    r = tsub.add_parser("rpm", help="train the Rolling Prediction Model (preset 3-head-hands)", description=__doc__)
    _common(r, "runs/rpm")
    r.set_defaults(func=_train_rpm)
    t = _perceptron_parser(
        tsub,
        "stance",
        "train the gait planner's stance classifier (which foot stands, from head and hands)",
        "Train the stance classifier (engine/models/stance.py) on the train split of prepared "
        "data and print its accuracy and the arm-swing rule's on the validation split.",
        hidden=128,
    )
    t.set_defaults(func=_train_stance)
    h = _perceptron_parser(
        tsub,
        "heading",
        "train the heading network (the pelvis heading from six position-only trackers)",
        "Train the heading network (engine/models/heading.py) on the train split of prepared data "
        "and print its mean heading error and the feet-and-hands facing's on the validation split.",
        hidden=256,
    )
    h.add_argument("--stride", type=int, default=4, help="every this many frames of a take is a sample (default 4)")
    h.set_defaults(func=_train_heading)
    n = tsub.add_parser(
        "tracker-net",
        help="train the tracker prior's networks (a latent from the trackers' last half second)",
        description="Train one network per tracker combination (engine/solver/tracker_net.py) on the train split "
        "of prepared data, with the latents of the shipped VAE (or --vae), and print each one's latent error on "
        "the validation split.",
    )
    n.add_argument("--data", type=Path, default=Path("prepared"), help="output of `data prepare` (default: prepared)")
    n.add_argument(
        "--out", type=Path, default=Path("runs/tracker_nets.npz"), help="networks file (default: runs/tracker_nets.npz)"
    )
    n.add_argument("--vae", type=Path, help="VAE weights whose latents the networks learn (default: the shipped one)")
    n.add_argument(
        "--presets",
        default="6,4,3-head-hands,3-hip-hands",
        help="sensor presets whose 6-DoF tracker combinations get a network (default: 6,4,3-head-hands,3-hip-hands)",
    )
    n.add_argument("--hidden", type=int, default=512, help="width of the two hidden layers (default 512)")
    n.add_argument("--epochs", type=int, default=20, help="passes over the samples (default 20)")
    n.add_argument("--stride", type=int, default=4, help="every N-th frame of each take is a sample (default 4)")
    n.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    n.add_argument(
        "--pose-weight",
        type=float,
        default=0.0,
        help="weight of the decoded poses' rotation difference beside the latent error (default 0)",
    )
    n.set_defaults(func=_train_tracker_net)
    p.set_defaults(func=lambda args: p.print_help() or 0)


def _direct(args: argparse.Namespace) -> dict:
    from engine.validation import check_args, check_output_dir

    check_args(args)
    check_output_dir(args.out)
    return {k: getattr(args, k) for k in ("epochs", "batch_size", "lr", "minutes", "seed")}


def _train_vae(args: argparse.Namespace) -> int:
    from engine.config import load_config
    from engine.training.vae import VAETrainConfig, train_vae

    cfg = load_config(VAETrainConfig, args.config, args.set, **_direct(args))
    meta = train_vae(args.data, args.out, cfg, resume=args.resume, progress=not args.quiet, device=args.device)
    if meta:
        print(
            f"{args.out}/vae.pt: {meta.get('epochs')} epochs, {meta.get('minutes')} min, "
            f"val {meta.get('val_pos_cm', float('nan')):.2f} cm / {meta.get('val_rot_deg', float('nan')):.2f} deg"
        )
    return 0


def _train_predictor(args: argparse.Namespace) -> int:
    from engine.config import load_config
    from engine.training.predictor import PredictorTrainConfig, train_predictor

    cfg = load_config(PredictorTrainConfig, args.config, args.set, **_direct(args))
    meta = train_predictor(
        args.data, args.vae, args.out, cfg, resume=args.resume, progress=not args.quiet, device=args.device
    )
    if meta:
        print(
            f"{args.out}/predictor.pt: {meta.get('epochs')} epochs, {meta.get('minutes')} min, "
            f"val latent MSE {meta.get('val_mse', float('nan')):.4g}"
        )
    return 0


def _train_sparseposer(args: argparse.Namespace) -> int:
    from engine.config import load_config
    from engine.training.sparseposer import SparsePoserTrainConfig, train_sparseposer

    cfg = load_config(SparsePoserTrainConfig, args.config, args.set, **_direct(args))
    meta = train_sparseposer(args.data, args.out, cfg, resume=args.resume, progress=not args.quiet)
    if meta:
        print(
            f"{args.out}/sparseposer.pt: {meta.get('epochs')} epochs, {meta.get('minutes')} min, "
            f"val {meta.get('val_pos_cm', float('nan')):.2f} cm (generator alone "
            f"{meta.get('val_gen_pos_cm', float('nan')):.2f} cm)"
        )
    return 0


def _train_rpm(args: argparse.Namespace) -> int:
    from engine.config import load_config
    from engine.training.rpm import RPMTrainConfig, train_rpm

    cfg = load_config(RPMTrainConfig, args.config, args.set, **_direct(args))
    meta = train_rpm(args.data, args.out, cfg, resume=args.resume, progress=not args.quiet)
    if meta:
        print(
            f"{args.out}/rpm.pt: {meta.get('epochs')} epochs, {meta.get('minutes')} min, "
            f"val {meta.get('val_pos_cm', float('nan')):.2f} cm"
        )
    return 0


def _train_stance(args: argparse.Namespace) -> int:
    from engine.errors import UserError
    from engine.training.stance import accuracy, load_samples, train_stance
    from engine.validation import check_args

    check_args(args)
    if not 1 <= args.hidden <= 4096:
        raise UserError(f"--hidden: {args.hidden} is not a layer width from 1 to 4096")
    train = load_samples(args.data, "train")
    val = load_samples(args.data, "val")
    model = train_stance(train, hidden=args.hidden, epochs=args.epochs, seed=args.seed)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    model.save(args.out)
    a = accuracy(model, val)
    print(
        f"{args.out}: {len(train.y)} training samples; validation ({int(a['samples'])} samples): "
        f"stance right {100 * a['model']:.1f} %, the arm-swing rule {100 * a['arms']:.1f} % "
        f"(it answers {100 * a['arms_coverage']:.0f} % of them)"
    )
    return 0


def _train_heading(args: argparse.Namespace) -> int:
    from engine.errors import UserError
    from engine.training.heading import angle_error_deg, load_samples, train_heading
    from engine.validation import check_args

    check_args(args)
    for name, lo, hi in (("hidden", 1, 4096), ("epochs", 1, 10_000), ("stride", 1, 1000)):
        if not lo <= getattr(args, name) <= hi:
            raise UserError(f"--{name}: {getattr(args, name)} is not a whole number from {lo} to {hi}")
    train = load_samples(args.data, "train", stride=args.stride)
    val = load_samples(args.data, "val", mirrored=False)
    model = train_heading(train, hidden=args.hidden, epochs=args.epochs, seed=args.seed)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    model.save(args.out)
    print(
        f"{args.out}: {len(train.x)} training samples; validation ({len(val.x)} frames): mean heading error "
        f"{angle_error_deg(model, val).mean():.2f} deg, the feet-and-hands facing {angle_error_deg(None, val).mean():.2f}"
    )
    return 0


def _train_tracker_net(args: argparse.Namespace) -> int:
    import time

    from tqdm import tqdm

    from engine.errors import UserError
    from engine.input_files import file_sha256
    from engine.models import load_default_models, load_models
    from engine.models.loading import DEFAULT_VAE
    from engine.solver.tracker_net import TrackerNets
    from engine.solver.tracker_prior import combination
    from engine.tracking import parse_sensors
    from engine.training.tracker_net import latent_mse, load_takes, samples, train_net

    for name, lo, hi in (("hidden", 1, 4096), ("epochs", 1, 10_000), ("stride", 1, 1000)):
        if not lo <= getattr(args, name) <= hi:
            raise UserError(f"--{name}: {getattr(args, name)} is not from {lo} to {hi}")
    combos: list[tuple[str, ...]] = []
    for preset in args.presets.split(","):
        c = combination(s.joint for s in parse_sensors(preset.strip()) if s.dof == 6)
        if c is None:
            raise UserError(f"--presets: {preset!r} has no hips or head tracker among two or more 6-DoF trackers")
        if c not in combos:
            combos.append(c)
    vae_file = args.vae or DEFAULT_VAE
    vae = (load_models(args.vae) if args.vae else load_default_models()).vae
    t0 = time.monotonic()
    train, val = load_takes(args.data, "train", vae), load_takes(args.data, "val", vae)
    print(
        f"{len(train.latents)} training and {len(val.latents)} validation takes encoded, {time.monotonic() - t0:.0f} s"
    )
    nets = {}
    for joints in combos:
        x, z = samples(train, joints, args.stride)
        bar = tqdm(total=args.epochs, desc="+".join(joints), unit="epoch")

        def report(epoch: int, mse: float, bar=bar) -> None:
            bar.set_postfix(mse=f"{mse:.4f}")
            bar.update()

        nets[joints] = net = train_net(
            joints,
            x,
            z,
            args.hidden,
            args.epochs,
            seed=args.seed,
            progress=report,
            decoder=vae,
            pose_weight=args.pose_weight,
        )
        bar.close()
        vx, vz = samples(val, joints, args.stride)
        print(f"{'+'.join(joints)}: {len(x)} samples, validation latent MSE {latent_mse(net, vx, vz):.4f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    TrackerNets(nets, file_sha256(vae_file)).save(args.out)
    print(f"{args.out}: {len(nets)} networks, {(time.monotonic() - t0) / 60:.1f} min")
    return 0
