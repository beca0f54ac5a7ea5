"""The workflow's layout (snakemake-workflows): config/README.md documents every setting of the config
schema with the default config/config.yaml gives it, and the small configs of .test/ are valid."""

import re

import pytest
import yaml

from conftest import ROOT

SCHEMA = yaml.safe_load((ROOT / "workflow" / "schemas" / "config.schema.yaml").read_text())
CONFIG = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
README = (ROOT / "config" / "README.md").read_text()


def settings(props, prefix=""):
    """Every setting the schema names, dotted (``sampler.walkers``), and its schema."""
    for key, spec in props.items():
        yield prefix + key, spec
        yield from settings(spec.get("properties", {}), f"{prefix}{key}.")


def rows():
    """config/README.md's table rows by setting: its cells after the name (unit, default, constraint, meaning)."""
    found = {}
    for line in README.splitlines():
        match = re.match(r"^\| `([\w.]+)` \|(.*)\|$", line)
        if match:
            found[match.group(1)] = [c.strip() for c in match.group(2).split("|")]
    return found


SETTINGS = dict(settings(SCHEMA["properties"]))


def test_config_readme_documents_every_setting_of_the_schema_and_no_other():
    documented = rows()
    assert sorted(set(SETTINGS) - set(documented)) == [], "in the schema, not in config/README.md"
    assert sorted(set(documented) - set(SETTINGS)) == [], "in config/README.md, not in the schema"
    assert all(len(cells) == 4 for cells in documented.values())


def default_of(key):
    """What a run takes for ``key`` when nothing overrides it: config/config.yaml's value, else the schema's
    default (Snakemake fills it in), else None (the effect's declaration holds)."""
    value = CONFIG
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            return SETTINGS[key].get("default")
        value = value[part]
    return value


@pytest.mark.parametrize("key", sorted(k for k, spec in SETTINGS.items() if "properties" not in spec))
def test_config_readme_gives_the_default_a_run_takes(key):
    unit, default, constraint, _ = rows()[key]
    assert unit and constraint
    assert (None if default == "none" else yaml.safe_load(default.strip("`"))) == default_of(key)


def test_the_output_schemas_refuse_what_a_script_could_not_read():
    from gyrocal.io.outputs import output_errors
    check = {"check": "converged", "passed": True, "why": "every parameter converged"}
    verdict = {"campaign": "mom", "model": "baseline", "verdict": "GO", "checks": [check]}
    assert output_errors(verdict, "verdict") == []
    assert output_errors({**verdict, "verdict": "go"}, "verdict") == ["verdict: 'go' is not one of ['GO', 'NO-GO']"]
    assert output_errors({**verdict, "checks": [{**check, "passed": "yes"}]}, "verdict") == \
        ["checks.0.passed: 'yes' is not of type 'boolean'"]
    refusal = {"model": "g_sensitivity", "status": "refused", "step": "point_estimate", "reason": "no acc_x"}
    assert output_errors(refusal, "diagnostics") == output_errors(refusal, "sampler") == []
    assert output_errors({**refusal, "status": "failed"}, "sampler")  # neither a record nor a refusal
    assert output_errors({"converged": True}, "sampler")
