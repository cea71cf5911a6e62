"""The command line shared by ``python -m pusht.dreamer`` and ``python -m pusht.loop``: one flag
per ``Config`` field (its help is the field's documented meaning and real default), plus the cache,
quiet and Rerun switches. A bad value is refused with usage, before anything runs.
"""

from __future__ import annotations

import argparse
from dataclasses import fields
from pathlib import Path

import torch

from .config import Config, field_docs, make_config
from .imagination import WIRINGS
from .record import RERUN_MISSING, rerun_available
from .world_model import PREDICTS

DESCRIPTION = "The chapter's whole pipeline in one command."
CHOICES = {"critic_wiring": WIRINGS, "wm_predicts": PREDICTS, "loop_wm": ("continue", "retrain"),
           "loop_actor": ("continue", "retrain")}


def build_parser(prog: str = "python -m pusht.dreamer", description: str = DESCRIPTION) -> argparse.ArgumentParser:
    docs = field_docs()
    # Each config flag's help states its real default; argparse's own would print "None", the
    # marker for "not given" that lets --smoke fill in only what the user left alone.
    p = argparse.ArgumentParser(prog=prog, description=description)
    defaults = Config()
    for f in fields(Config):
        default = getattr(defaults, f.name)
        if f.name == "smoke":
            p.add_argument("--smoke", action="store_true", help=docs.get("smoke"))
            continue
        kind = {bool: None, int: int, float: float, str: str}.get(type(default), Path)
        # default=None marks "not given", so --smoke can fill in only what the user left alone.
        p.add_argument(f"--{f.name}", type=kind, default=None, help=f"{docs.get(f.name, '')} "
                       f"(default: {default})", choices=CHOICES.get(f.name))
    p.add_argument("--cache", type=Path, default=None,
                   help="folder for cached expert data (default: $PUSHT_CACHE or ~/.cache/pusht-dreamer)")
    p.add_argument("--no-cache", action="store_true", help="always collect expert data afresh")
    p.add_argument("--quiet", action="store_true", help="print only the final report")
    p.add_argument("--rerun", action="store_true",
                   help="also write <out>/dreamer.rrd, a Rerun recording of both worlds and the training "
                        "curves (needs the optional rerun-sdk package)")
    return p


def parse_config(argv=None, prog: str = "python -m pusht.dreamer", parser=None, base=None):
    """The config the flags ask for, and the parsed arguments. ``parser``: one made by
    :func:`build_parser` with a command's own flags added; ``base(smoke) -> dict``: that command's
    own defaults for some config fields (``pusht.plan``'s recipe), under the flags the user gave."""
    parser = parser or build_parser(prog)
    args = parser.parse_args(argv)
    given = {f.name: getattr(args, f.name) for f in fields(Config)
             if f.name != "smoke" and getattr(args, f.name) is not None}
    if "out" not in given and "seed" in given:
        given["out"] = Path(f"runs/seed{given['seed']}")      # each seed gets its own folder
    try:
        cfg = make_config(smoke=args.smoke, **{**(base(args.smoke) if base else {}), **given})
    except ValueError as e:
        parser.error(str(e).splitlines()[0])
    if args.rerun and not rerun_available():     # say so now, not after the whole run
        parser.error(RERUN_MISSING)
    try:
        torch.empty(0, device=cfg.device)       # fail here, with usage, if the device is unusable
    except Exception as e:  # noqa: BLE001  torch raises RuntimeError or AssertionError here
        parser.error(f"--device {cfg.device} is not usable here ({str(e).splitlines()[0]}); "
                     f"use --device cpu")
    return cfg, args
