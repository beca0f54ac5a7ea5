"""The ``gyrocal`` command: simulate a campaign, validate one."""

import argparse
import sys

from . import __version__


def main(argv=None):
    parser = argparse.ArgumentParser(prog="gyrocal", description=__doc__)
    parser.add_argument("--version", action="version", version=f"gyrocal {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="simulate a campaign from a scenario YAML")
    sim.add_argument("scenario")
    sim.add_argument("outdir")
    sim.add_argument("--seed", type=int, default=None, help="default: the scenario's seed")
    val = sub.add_parser("validate", help="check a campaign directory against the contract")
    val.add_argument("directory")
    args = parser.parse_args(argv)

    from .telemetry import TelemetryError
    try:
        if args.command == "simulate":
            from .simulate import run
            campaign, truth = run(args.scenario, args.outdir, args.seed)
            print(f"wrote {args.outdir}/campaign ({len(campaign.maneuvers)} maneuvers, seed {truth['seed']}) "
                  f"and {args.outdir}/truth.json")
        elif args.command == "validate":
            from .consistency import read_checked, summary
            print(summary(*read_checked(args.directory)))
    except (TelemetryError, ValueError, FileNotFoundError) as exc:
        print(f"gyrocal {args.command}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
