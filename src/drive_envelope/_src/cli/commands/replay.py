"""``drive-envelope replay LOG... --stand STAND``: the error a stand gives on logs, in an engine."""

from __future__ import annotations

import argparse
from typing import Any

from drive_envelope._src.cli.common import add_format_argument


def register(subparsers: Any) -> None:
    """Add the ``replay`` command."""
    parser = subparsers.add_parser(
        "replay",
        help="replay bench logs through a stand (identify -o) and print each log's error",
        description=(
            "Replay each log's commands (target_position, target_velocity, torque_enable; a sidecar's "
            "kp_duty_per_rad) from its first sample through the stand, as identify replays them, and "
            "print the mean absolute position and velocity error per log. A stand written by "
            "identify -o replays its held-out logs to identify's validation errors."
        ),
    )
    parser.add_argument(
        "logs", nargs="+", metavar="LOG", help="bench logs (.csv, .tsv, .txt, also .gz; .parquet)"
    )
    parser.add_argument(
        "--stand", required=True, metavar="STAND", help="stand file (identify -o, or one written by hand)"
    )
    parser.add_argument(
        "--engine",
        choices=("reference", "physx", "mujoco"),
        default="reference",
        help="replay in the reference solver (default), real PhysX (ovphysx) or MuJoCo with the plugin",
    )
    add_format_argument(parser, ("text", "json"), "the errors as text or as one JSON object (SI)")
    from drive_envelope._src.analysis.options import add_bag_arguments

    add_bag_arguments(parser, joint=True)
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from drive_envelope._src.analysis.options import bag_from_args
    from drive_envelope._src.cli.common import print_json, printed_warnings
    from drive_envelope._src.identify.playback import playback_text, playback_to_dict, replay_logs
    from drive_envelope._src.identify.stand import StandWarning

    with printed_warnings(StandWarning, once=False):
        result = replay_logs(
            args.logs, args.stand, engine=args.engine, bag=bag_from_args(args), joint=args.joint
        )
    if args.format == "json":
        print_json(playback_to_dict(result))
    else:
        print(playback_text(result))
    return 0
