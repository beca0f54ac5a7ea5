"""``gyrocal run``: the workflow with settings from the command line. Snakemake's own ``--config`` takes
top-level keys only (``--config sampler.walkers=32`` fails in its parser), so each ``--set KEY.SUB=VALUE``
becomes one key of a small config file given to Snakemake last, over ``config/config.yaml`` and any
``--configfile``; the merged config is checked against the workflow's schema first, so a bad value is
refused naming its key before any job starts."""

import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import yaml

from gyrocal.errors import InputError

__all__ = ["check_config", "merged_config", "overlay", "run", "workflow_root"]

SCHEMA = Path("workflow", "schemas", "config.schema.yaml")
"""The workflow's config schema, under the repository (the one the Snakefile validates with)."""


def workflow_root() -> Path:
    """The repository whose workflow runs: the current directory where it holds ``workflow/Snakefile``
    (as Snakemake finds it), else the one this package sits in (a checkout with ``src/gyrocal``)."""
    here = Path.cwd()
    if (here / "workflow" / "Snakefile").is_file():
        return here
    return Path(__file__).resolve().parents[3]


def overlay(assignments) -> dict:
    """The nested config that ``KEY.SUB=VALUE`` assignments set (each VALUE read as YAML: ``64`` a number,
    ``true`` a boolean, ``[a, b]`` a list, ``""`` empty text); later assignments win."""
    out = {}
    for text in assignments:
        key, sep, value = text.partition("=")
        parts = key.strip().split(".")
        if not sep or not all(parts):
            raise InputError(f"--set {text!r}: give KEY=VALUE, a nested key with dots (sampler.walkers=64)")
        try:
            parsed = yaml.safe_load(value) if value.strip() else ""
        except yaml.YAMLError as exc:
            raise InputError(f"--set {text!r}: the value is not YAML ({exc.problem})") from None
        node = out
        for part in parts[:-1]:
            if not isinstance(node.get(part), dict):
                node[part] = {}
            node = node[part]
        node[parts[-1]] = parsed
    return out


def _merge(base: dict, update: dict) -> dict:
    """``update`` over ``base`` key by key (as Snakemake merges config files: nested mappings merged)."""
    out = dict(base)
    for key, value in update.items():
        out[key] = _merge(out[key], value) if isinstance(value, dict) and isinstance(out.get(key), dict) else value
    return out


def merged_config(root: Path, configfiles, sets: dict) -> dict:
    """The config a run takes: ``config/config.yaml``, each of ``configfiles`` over it, then ``sets``."""
    config = {}
    for path in [Path(root, "config", "config.yaml"), *map(Path, configfiles)]:
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
        except (OSError, yaml.YAMLError) as exc:
            raise InputError(f"{path}: cannot be read as a config ({exc})") from None
        if not isinstance(data, dict):
            raise InputError(f"{path}: a config is a mapping of settings, not {type(data).__name__}")
        config = _merge(config, data)
    return _merge(config, sets)


def check_config(config: dict, schema_path: Path, sets: dict):
    """Refuse a config the workflow's schema refuses, with the schema's message and the key it is about
    (and which ``--set`` gave it, where one did)."""
    import jsonschema
    from jsonschema.exceptions import best_match

    schema = yaml.safe_load(Path(schema_path).read_text(encoding="utf-8"))
    error = best_match(jsonschema.Draft202012Validator(schema).iter_errors(config))
    if error is None:
        return
    keys = [str(k) for k in error.absolute_path]
    message = error.message
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        unknown = sorted(str(k) for k in error.instance if k not in error.schema.get("properties", {}))
        keys += unknown[:1]
        message = f"no such setting; {'.'.join(keys[:-1]) or 'the config'} takes {sorted(error.schema.get('properties', {}))}"
    key = ".".join(keys) or "the config"
    node, given = sets, bool(keys)
    for k in keys:
        if not isinstance(node, dict) or k not in node:
            given = False
            break
        node = node[k]
    origin = " (from --set)" if given else ""
    raise InputError(f"setting {key}{origin}: {message} ({schema_path})")


def run(sets=(), configfiles=(), snakemake_args=()) -> int:
    """Run the workflow (``snakemake`` with ``snakemake_args``) with ``configfiles`` and the ``--set``
    assignments ``sets`` over the default config, once the merged config passes the schema; Snakemake's
    exit status. Refused, saying how to install it, where Snakemake is not installed (the ``workflow``
    extra: the library alone does not need it)."""
    if importlib.util.find_spec("snakemake") is None:
        raise InputError("gyrocal run needs Snakemake, which the library does not: install the workflow extra, "
                         "pip install -e \".[workflow]\" (or pip install snakemake)")
    root = workflow_root()
    given = overlay(sets)
    check_config(merged_config(root, configfiles, given), root / SCHEMA, given)
    args = list(snakemake_args)
    if not any(a in ("-s", "--snakefile") or a.startswith("--snakefile=") for a in args):
        args = ["--snakefile", str(root / "workflow" / "Snakefile"), *args]
    handle, path = tempfile.mkstemp(prefix="gyrocal-set-", suffix=".yaml")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            yaml.safe_dump(given, out)
        files = [*map(str, configfiles), path] if given else list(map(str, configfiles))
        tail = ["--configfile", *files] if files else []
        return subprocess.call([sys.executable, "-m", "snakemake", *args, *tail])
    finally:
        os.unlink(path)
