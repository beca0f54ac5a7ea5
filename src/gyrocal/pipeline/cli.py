"""The ``gyrocal`` command: simulate, import or validate a campaign; run the workflow with settings from the
command line; compare two calibrations or fit several jointly; plan a campaign; measure a gyro's noise at
rest; check the linear model against the exact one."""

import argparse
import os
import sys

from gyrocal import __version__
from gyrocal.errors import InputError

__all__ = ["entry", "main"]


def main(argv=None):
    parser = argparse.ArgumentParser(prog="gyrocal", description=__doc__)
    parser.add_argument("--version", action="version", version=f"gyrocal {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    sim = sub.add_parser("simulate", help="simulate a campaign from a scenario YAML")
    sim.add_argument("scenario")
    sim.add_argument("outdir")
    sim.add_argument("--seed", type=int, default=None, help="default: the scenario's seed")
    imp = sub.add_parser("import", help="write a campaign directory from recordings (CSV, MATLAB .mat, HDF5), "
                                        "through a mapping")
    imp.add_argument("mapping", help="a shipped mapping (repoimu, broad) or a mapping file (.yaml)")
    imp.add_argument("outdir")
    imp.add_argument("files", nargs="+", help="one noise group per file, named after its stem, and one "
                                              "maneuver (or one per stretch between its rests)")
    imp.add_argument("--reference-interval", type=float, default=None, metavar="S",
                     help="keep the reference only every S seconds (0: every row); default: the mapping's "
                          "reference.sample_interval_s")
    val = sub.add_parser("validate", help="check a campaign directory against the contract")
    val.add_argument("directory")
    val.add_argument("--config", default="config/config.yaml",
                     help="gyrocal config whose sampler.block_s every maneuver must fit, as the posterior needs "
                          "(default config/config.yaml; without it that check is left to the posterior step)")
    cmp_ = sub.add_parser("compare-campaigns", help="compare two calibration.csv parameter by parameter")
    cmp_.add_argument("first")
    cmp_.add_argument("second")
    cmp_.add_argument("--z-max", type=float, default=3.0, help="agreement limit on |z| (default 3)")
    jnt = sub.add_parser("joint", help="one calibration from several runs of one unit, and their consistency test")
    jnt.add_argument("runs", nargs="+", metavar="RUN", help="two or more runs' results/<campaign> folders")
    jnt.add_argument("--out", required=True, help="where calibration.csv and consistency.json go")
    jnt.add_argument("--model", default="baseline", help="the model variant (default baseline)")
    jnt.add_argument("--config", default="config/config.yaml",
                     help="gyrocal config whose priors the joint fit takes once (default config/config.yaml; "
                          "without it the effects' declared priors)")
    jnt.add_argument("--level", type=float, default=0.05, help="the consistency test's level (default 0.05)")
    aln = sub.add_parser("allan", help="the gyro noise of a static recording: Allan deviation and angle random walk")
    aln.add_argument("mapping", help="a shipped mapping (repoimu) or a mapping file (.yaml)")
    aln.add_argument("file", help="a recording with the gyros at rest")
    lin = sub.add_parser("linearity", help="the exact model against the linear one where the posterior lives")
    lin.add_argument("results", help="a run's results/<campaign> folder")
    lin.add_argument("--model", default="baseline", help="the model variant (default baseline)")
    lin.add_argument("--plugin", action="append", default=[], metavar="FILE", help="a plugin file the model uses")
    pln = sub.add_parser("plan", help="predict what a planned campaign (a scenario YAML) will tell, before flying it")
    pln.add_argument("scenarios", nargs="+", metavar="SCENARIO", help="one scenario, or two to compare side by side")
    pln.add_argument("--out", default=None, help="where plan.csv, plan_detection.csv and plan.png go "
                     "(default results/plan)")
    pln.add_argument("--config", default="config/config.yaml", help="gyrocal config (priors, models, thresholds)")
    pln.add_argument("--model", default="baseline", help="the model variant to plan for (default baseline)")
    run = sub.add_parser("run", allow_abbrev=False,
                         help="run the workflow (snakemake) with settings from the command line: --set KEY.SUB=VALUE",
                         description="Run the workflow: every argument gyrocal does not take goes to snakemake "
                                     "(gyrocal run --cores 2 --set sampler.walkers=32). Each --set is checked "
                                     "against workflow/schemas/config.schema.yaml before any job.")
    run.add_argument("--set", action="append", default=[], metavar="KEY.SUB=VALUE", dest="sets",
                     help="one setting, nested keys joined by dots, its value read as YAML "
                          "(sampler.walkers=64, report.physical_bound_ppm=500); repeat for more")
    run.add_argument("--configfile", action="append", default=[], metavar="FILE",
                     help="a config file over config/config.yaml (before every --set); repeat for more")
    args, rest = parser.parse_known_args(argv)
    if rest and args.command != "run":
        parser.error(f"unrecognized arguments: {' '.join(rest)}")
    if args.command == "plan" and len(args.scenarios) > 2:
        parser.error("plan takes one scenario, or two to compare")

    try:
        if args.command == "simulate":
            from gyrocal.simulation.simulate import run
            campaign, truth = run(args.scenario, args.outdir, args.seed)
            print(f"wrote {args.outdir}/campaign ({len(campaign.maneuvers)} maneuvers, seed {truth['seed']}) "
                  f"and {args.outdir}/truth.json")
        elif args.command == "import":
            from gyrocal.io.importer import import_files, report
            print(report(*import_files(args.mapping, args.outdir, args.files, args.reference_interval), args.outdir))
        elif args.command == "validate":
            from gyrocal.checks import read_checked, summary
            print(summary(*read_checked(args.directory, block_s=_block_s(args.config))))
        elif args.command == "compare-campaigns":
            from gyrocal.criticism.agreement import compare_files
            text, agree = compare_files(args.first, args.second, args.z_max)
            print(text)
            return 0 if agree else 1
        elif args.command == "joint":
            from gyrocal.pipeline.steps.joint import run
            text, consistent = run(args.runs, args.out, args.model, _priors(args.config), args.level)
            print(text)
            return 0 if consistent else 1
        elif args.command == "allan":
            from gyrocal.io.importer import read_file, read_mapping
            from gyrocal.planning.allan import static_report
            mapping = read_mapping(args.mapping)
            print(static_report(read_file(args.file, mapping), list(mapping["gyro"]["columns"]), args.file))
        elif args.command == "linearity":
            from gyrocal.pipeline.readback import linearity_report
            print(linearity_report(args.results, args.model, args.plugin))
        elif args.command == "run":
            from gyrocal.pipeline.workflow_run import run
            return run(args.sets, args.configfile, rest)
        elif args.command == "plan":
            import matplotlib
            matplotlib.use("Agg")
            from gyrocal.pipeline.steps.plan import DEFAULT_OUT, run
            print(run(args.scenarios, args.config, args.out or DEFAULT_OUT, args.model))
    except BrokenPipeError:
        raise  # the reader stopped early: `entry` ends quietly
    except (InputError, ValueError, OSError) as exc:
        print(f"gyrocal {args.command}: error: {exc}", file=sys.stderr)
        return 2
    return 0


def _block_s(config_path):
    """The sampler's leave-one-block-out block of a gyrocal config, or None where there is no config."""
    from pathlib import Path

    from gyrocal.io.yamlfile import load_yaml
    if not Path(config_path).is_file():
        return None
    return ((load_yaml(config_path) or {}).get("sampler") or {}).get("block_s")


def _priors(config_path):
    """The ``priors`` section of a gyrocal config, or None where there is no config."""
    from pathlib import Path

    from gyrocal.io.yamlfile import load_yaml
    if not Path(config_path).is_file():
        return None
    return (load_yaml(config_path) or {}).get("priors")


def entry():
    """The console script: `main`, and a reader that stops early (``gyrocal validate DIR | head -1``)
    ends the command quietly, as Unix tools do, not with a traceback."""
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        code = 0
    return code


if __name__ == "__main__":
    sys.exit(entry())
