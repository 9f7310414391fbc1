"""`nift train`: train the NIF (--target scf) or the NDF (--target occ) field."""
from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from app.console.output import print_figures

NAME = "train"
HELP = "train a neural field on `nift make-data` output: NIF (SCF) or NDF (occupancy)"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--target", required=True, choices=["scf", "occ"], help="scf = NIF, occ = NDF")
    p.add_argument("--data", type=Path, required=True, help="training data directory")
    p.add_argument("--eval-data", type=Path, help="held-out (test-split) data for the final metrics")
    p.add_argument("--out", type=Path, required=True, help="run directory: checkpoints, best and final weights")
    p.add_argument("--weights", type=Path, help="where to write the final weights + model card (default OUT/field.pt)")
    p.add_argument("--resume", action="store_true", help="continue from OUT/last.pt")
    p.add_argument("--epochs", type=int, help="passes over the data (default 10; 1 with --quick)")
    p.add_argument("--minutes", type=float, help="wall-clock budget; stops at a checkpoint when spent")
    p.add_argument("--lr", type=float, default=1e-4, help="Adam learning rate (paper: 1e-4)")
    p.add_argument("--lr-final", type=float, help="cosine decay of the learning rate to this over the budget")
    p.add_argument("--init", help="start from these weights (nif, ndf or a path); tensors of another shape "
                                  "(the head of another --scf-order) start fresh")
    p.add_argument("--batch-size", type=int, default=16)
    p.add_argument("--scf-order", type=int, default=5, help="SCF bands c_0..c_n the NIF predicts")
    p.add_argument("--threads", type=int, help="torch CPU threads (default: all cores)")
    p.add_argument("--seed", type=int, default=0, help="initialisation, batches, validation split")
    p.add_argument("--quick", action="store_true", help="a tiny model for one epoch (CI size)")
    p.add_argument("--json", action="store_true", help="print the model card as JSON")


FLAG_RANGES = (("epochs", 1, 100_000), ("minutes", 1e-3, 1e6), ("lr", 1e-12, 1.0), ("lr_final", 0.0, 1.0),
               ("batch_size", 1, 4096), ("scf_order", 0, 10), ("threads", 1, 1024))


def check_flags(args: argparse.Namespace) -> None:
    """Each numeric flag given is inside its range (a one-line error naming it), and --out and
    --weights are places a run could be written, before any data is read."""
    from app.io_utils import writable_directory, writable_file

    for name, low, high in FLAG_RANGES:
        value = getattr(args, name)
        if value is not None and not low <= value <= high:
            raise ValueError(f"--{name.replace('_', '-')} must be in [{low:g}, {high:g}], got {value}")
    writable_directory(args.out, "--out")
    if args.weights is not None:
        writable_file(args.weights, "--weights")


def config_from(args: argparse.Namespace):
    """The TrainConfig the arguments describe."""
    from app.nift.field import FieldConfig
    from app.training.train import TrainConfig

    field = FieldConfig(target=args.target, scf_order=args.scf_order)
    epochs = args.epochs if args.epochs is not None else (1 if args.quick else 10)
    values = dict(epochs=epochs, lr=args.lr, batch_size=args.batch_size,
                  minutes=args.minutes, lr_final=args.lr_final, seed=args.seed)
    if args.quick:
        field = FieldConfig(target=args.target, scf_order=args.scf_order, latent=8, encoder_width=8,
                            encoder_blocks=1, decoder_width=16, decoder_blocks=1, cloud_points=128)
        values.update(batch_size=2, query_points=64)
    return TrainConfig(field=field, **values)


def run(args: argparse.Namespace) -> int:
    import torch

    from app.training.train import train

    check_flags(args)
    if args.threads:
        torch.set_num_threads(args.threads)
    command = "nift " + " ".join(shlex.quote(a) for a in sys.argv[1:])
    card = train(config_from(args), args.data, args.out, eval_dir=args.eval_data, weights=args.weights,
                 resume=args.resume, progress=not args.json, command=command, init=args.init)
    if args.json:
        import json

        print(json.dumps({k: v for k, v in card.items() if k != "history"}, indent=2))
        return 0
    val, test = card["validation"], card.get("test", {})
    key = "scf_r2" if args.target == "scf" else "occ_accuracy"
    print_figures({"weights": str(args.weights or args.out / "field.pt"), "epochs": card["training"]["epochs"],
                   "seconds": card["training"]["seconds"], f"validation_{key}": val.get(key),
                   f"test_{key}": test.get(key), f"paper_{key}": card["paper"][key]}, False)
    return 0
