"""The documentation's commands and settings still exist: every `gyrocal <subcommand>`, script, config
file and `--config` key that README.md and docs/ show, and every setting they name as `section.key`."""

import contextlib
import io
import re

import pytest
import yaml

from gyrocal.errors import InputError
from gyrocal.pipeline import cli

from conftest import ROOT

PAGES = [ROOT / "README.md", ROOT / "config" / "README.md", *sorted((ROOT / "docs").rglob("*.md")),
         *sorted((ROOT / "examples").rglob("*.md"))]

NOT_SETTINGS = {"noise.group_sd"}
"""Names written like a setting (`section.key`) that are something else: a row of posterior_summary.csv."""

PLACEHOLDERS = {"key", "FILE"}
FILE_SUFFIXES = {"csv", "html", "json", "md", "nc", "npz", "png", "py", "yaml"}


def code(text: str) -> list:
    """The page's code: each line of its fenced and indented blocks, and each inline code span."""
    lines, fenced, in_block, previous_blank = [], False, False, True
    for line in text.splitlines():
        if line.lstrip().startswith("```"):
            fenced, in_block = not fenced, False
        elif fenced:
            lines.append(line.strip())
        else:
            in_block = line.startswith("    ") and line.strip() != "" and (previous_blank or in_block)
            if in_block:
                lines.append(line.strip())
        previous_blank = not line.strip()
    spans = re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))
    return [line for line in lines if line] + spans


def documented():
    """(page, code) for every line or span of code in the documentation."""
    return [(page.relative_to(ROOT), snippet) for page in PAGES for snippet in code(page.read_text())]


SNIPPETS = documented()


def subcommands() -> set:
    """The subcommands `gyrocal --help` lists."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        cli.main(["--help"])
    return set(re.search(r"\{([a-z,-]+)\}", out.getvalue()).group(1).split(","))


def schema(name: str) -> dict:
    return yaml.safe_load((ROOT / "workflow" / "schemas" / name).read_text())


def test_the_documentation_has_code_to_check():
    assert sum("gyrocal " in s for _, s in SNIPPETS) > 20 and sum("--config " in s for _, s in SNIPPETS) > 10


def test_every_documented_gyrocal_subcommand_exists():
    known = subcommands()
    used = {(page, m) for page, s in SNIPPETS for m in re.findall(r"(?:^|&& |\| |; )gyrocal ([a-z][a-z-]*)", s)}
    assert used, "no gyrocal command found in the documentation"
    assert not {(str(p), m) for p, m in used if m not in known}, known


def test_every_documented_config_override_is_a_setting():
    config, study = set(schema("config.schema.yaml")["properties"]), set(schema("study.schema.yaml")["properties"])
    wrong = []
    for page, s in SNIPPETS:
        for args in re.findall(r"--config((?: +[A-Za-z_][\w.]*=\S*)+)", s):
            keys = {a.split("=")[0] for a in args.split()} - PLACEHOLDERS
            known = study if "workflow/study/Snakefile" in s else config if "snakemake" in s else config | study
            wrong += [(str(page), k) for k in keys if k not in known]
    assert not wrong


def test_every_documented_gyrocal_run_setting_is_one_the_schema_accepts():
    from gyrocal.pipeline.workflow_run import SCHEMA, check_config, merged_config, overlay
    runs = [s for _, s in SNIPPETS if re.match(r"gyrocal run .*--set ", s)]
    assert len(runs) >= 2, "no documented gyrocal run --set command"
    for line in runs:
        sets = overlay(re.findall(r"--set (\S+)", line.split("#")[0]))
        check_config(merged_config(ROOT, [], sets), ROOT / SCHEMA, sets)  # refuses an unknown key or a bad value
    with pytest.raises(InputError, match=r"setting sampler\.walker: no such setting"):  # the check can fail
        check_config(merged_config(ROOT, [], overlay(["sampler.walker=32"])), ROOT / SCHEMA, {})


def test_every_documented_setting_section_key_exists():
    sections = {k: set(v["properties"]) for k, v in schema("config.schema.yaml")["properties"].items()
                if isinstance(v, dict) and "properties" in v}
    wrong = []
    for page, s in SNIPPETS:
        names = []
        if m := re.fullmatch(r"([a-z_]+)\.([a-z_]+)", s):
            names = [] if s in NOT_SETTINGS or m.group(2) in FILE_SUFFIXES else [(m.group(1), m.group(2))]
        elif m := re.fullmatch(r"([a-z_]+): *\{(.*)\}", s):
            depth, part, parts = 0, "", []
            for ch in m.group(2) + ",":
                depth += ch == "{"
                depth -= ch == "}"
                if ch == "," and depth == 0:
                    parts.append(part)
                    part = ""
                else:
                    part += ch
            names = [(m.group(1), p.split(":")[0].strip()) for p in parts]
        wrong += [(str(page), f"{a}.{b}") for a, b in names if a in sections and b not in sections[a]]
    assert not wrong


def test_every_documented_script_and_config_file_exists():
    """Every script and config file a page runs exists in the repository; a scratch file under /tmp is one
    the page's own code writes first."""
    missing = []
    for page, s in SNIPPETS:
        paths = re.findall(r"(?:^|[\s`(])python (?:-m \S+ )?([\w./-]+\.py)", s)
        paths += re.findall(r"(?:--configfile|snakemake -s) ([\w./-]+)", s)
        missing += [(str(page), p) for p in paths
                    if p not in PLACEHOLDERS and not p.startswith("/tmp/") and not (ROOT / p).exists()]
    assert not missing
