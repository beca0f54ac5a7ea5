"""Configuration files as a hostile or careless user writes them: every YAML file gyrocal reads goes
through one loader (no aliases, no duplicate keys, a bounded size) and a JSON Schema, and each
fault is refused naming the file and the line or key, in bounded time and memory."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest
import yaml

from gyrocal.io import importer, scenario, telemetry, yamlfile
from gyrocal.io.campaign_yaml import RESERVED_NAMES, TelemetryError, read_meta
from gyrocal.planning import plan

from conftest import DATA, ROOT

BOMB_SECONDS = 5.0
ADDRESS_SPACE = 2 << 30


@pytest.fixture
def meta_text(tiny):
    """The tiny campaign's campaign.yaml, as gyrocal writes it."""
    return (tiny[0] / "campaign.yaml").read_text()


def campaign_dir(tmp_path, text, name="campaign"):
    """A directory holding only ``campaign.yaml`` (what `read_meta` reads)."""
    directory = tmp_path / name
    directory.mkdir()
    (directory / "campaign.yaml").write_text(text)
    return directory


def refusal(directory) -> str:
    with pytest.raises(TelemetryError) as refused:
        read_meta(directory)
    message = str(refused.value)
    assert message.startswith(f"{directory / 'campaign.yaml'}: "), message
    return message


def line_of(text, fragment) -> int:
    return text[:text.index(fragment)].count("\n") + 1


def billion_laughs(levels=9) -> str:
    lines = ['a0: &a0 ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    lines += [f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, levels + 1)]
    return "\n".join(lines) + f"\nname: *a{levels}\n"


def test_an_anchor_bomb_in_name_is_refused_in_seconds_under_a_2_gb_address_space(tiny, tmp_path, meta_text):
    directory = tmp_path / "campaign"
    shutil.copytree(tiny[0], directory)
    (directory / "campaign.yaml").write_text(billion_laughs() + meta_text.replace("name: tiny\n", ""))
    code = "import sys; from gyrocal.pipeline.cli import main; sys.exit(main(sys.argv[1:]))"

    def limit():
        import resource
        resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))

    def cpu_seconds():  # the refusal's own CPU time: a shared machine's load does not stretch it
        import resource
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    start = cpu_seconds()
    out = subprocess.run([sys.executable, "-c", code, "validate", str(directory)], capture_output=True, text=True,
                         preexec_fn=limit, timeout=120, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    elapsed = cpu_seconds() - start
    assert out.returncode == 2, out.stderr
    assert elapsed < BOMB_SECONDS
    assert f"{directory / 'campaign.yaml'}: line 1: an anchor (&a0)" in out.stderr
    assert "Traceback" not in out.stderr and "MemoryError" not in out.stderr


def test_an_alias_anywhere_is_refused_at_its_line(tmp_path, meta_text):
    text = meta_text.replace("  t_start: 1350.0", "  t_start: *start").replace("t_start: 1020.0", "t_start: &start 1020.0")
    message = refusal(campaign_dir(tmp_path, text))
    assert f"line {line_of(text, '&start')}: an anchor (&start)" in message


def test_a_name_ending_in_a_newline_is_refused(tmp_path, meta_text):
    message = refusal(campaign_dir(tmp_path, meta_text.replace("name: tiny", 'name: "tiny\\n"')))
    assert "name: must be a name of letters, digits and '_' only" in message and "'tiny\\n' (line 1)" in message


def test_a_maneuver_id_ending_in_a_newline_is_refused(tmp_path, meta_text):
    text = meta_text.replace("- id: yaw_neg", '- id: "yaw_neg\\n"')
    message = refusal(campaign_dir(tmp_path, text))
    assert "maneuvers[1] ('yaw_neg\\n').id: must be an id of letters" in message
    assert f"(line {line_of(text, 'yaw_neg')})" in message


def test_a_duplicated_maneuvers_key_is_refused_naming_both_lines(tmp_path, meta_text):
    extra = "maneuvers:\n- {id: late, axis: yaw, direction: '+', t_start: 5000.0, t_end: 5100.0}\n"
    text = meta_text + extra
    message = refusal(campaign_dir(tmp_path, text))
    first, second = line_of(text, "maneuvers:"), line_of(text, extra)
    assert f"line {second}: the key 'maneuvers' is given twice in one mapping, on line {first} and on line {second}" \
        in message


def test_a_duplicated_key_deep_inside_is_refused(tmp_path, meta_text):
    text = meta_text.replace("  sigma_about_arcsec: 20.0\n", "  sigma_about_arcsec: 20.0\n  sigma_about_arcsec: 5.0\n")
    message = refusal(campaign_dir(tmp_path, text))
    assert "the key 'sigma_about_arcsec' is given twice" in message


@pytest.mark.parametrize("name", RESERVED_NAMES)
def test_a_reserved_name_is_refused(name, tmp_path, meta_text):
    message = refusal(campaign_dir(tmp_path, meta_text.replace("name: tiny", f"name: {name}")))
    assert "name: must be a name of letters, digits and '_' only, at most 64 of them" in message
    assert f"got '{name}' (line 1)" in message


@pytest.mark.parametrize("name, said", [
    ("a" * 300, "at most 64 of them"),  # Snakemake's run: "File name too long"
    ("run_" + "0" * 24, "not ending in one part repeated 20 times or more"),  # Snakemake's run: PeriodicWildcardError
])
def test_a_name_snakemake_cannot_use_is_refused_up_front(name, said, tmp_path, meta_text, capsys):
    from gyrocal.pipeline.cli import main
    directory = campaign_dir(tmp_path, meta_text.replace("name: tiny", f"name: {name}"))
    message = refusal(directory)
    assert said in message and "(line 1)" in message
    assert main(["validate", str(directory), "--config", str(ROOT / "config" / "config.yaml")]) == 2
    assert said in capsys.readouterr().err


def test_names_within_the_bounds_pass(tmp_path, meta_text):
    for name in ("abc" * 21 + "d", "run_" + "0" * 19, "run_" + "01" * 19):
        assert read_meta(campaign_dir(tmp_path, meta_text.replace("name: tiny", f"name: {name}"), name))["name"] == name


@pytest.mark.parametrize("dirname, said", [
    ("c" * 70, "70 characters, over the 64 a campaign name may have"),
    ("run_" + "0" * 24, "ends in '0' repeated 24 times, which Snakemake refuses"),
])
def test_a_directory_name_snakemake_cannot_use_is_refused_without_name_key(dirname, said, tmp_path, meta_text):
    message = refusal(campaign_dir(tmp_path, meta_text.replace("name: tiny\n", ""), name=dirname))
    assert "name (from the directory's): " in message and said in message


def test_a_directory_named_as_a_reserved_name_without_name_key_is_refused(tmp_path, meta_text):
    message = refusal(campaign_dir(tmp_path, meta_text.replace("name: tiny\n", ""), name="fleet"))
    assert "name (from the directory's): 'fleet' is reserved: results/fleet is where gyrocal writes a fleet's summary" \
        in message


def test_a_file_over_the_size_bound_is_refused_unparsed(tmp_path, meta_text):
    text = meta_text + "# padding\n" * (yamlfile.MAX_BYTES // 10)
    message = refusal(campaign_dir(tmp_path, text))
    assert f"is larger than {yamlfile.MAX_BYTES} bytes" in message


def test_a_directory_given_as_campaign_yaml_is_refused(tmp_path):
    (tmp_path / "campaign" / "campaign.yaml").mkdir(parents=True)
    assert "is not a file (a directory?)" in refusal(tmp_path / "campaign")


def test_invalid_yaml_names_its_line_and_column(tmp_path, meta_text):
    text = meta_text.replace("  dtg1_roll:\n", "  dtg1_roll: [\n")
    message = refusal(campaign_dir(tmp_path, text))
    assert "not valid YAML" in message and ": line " in message and "column" in message


def test_a_campaign_schema_violation_names_the_key_path_and_line(tmp_path, meta_text):
    text = meta_text.replace("  t_end: 1660.0\n", "  t_end: 1660.0\n  rate_deg_s: 0.5\n")
    message = refusal(campaign_dir(tmp_path, text))
    assert f"maneuvers[1] (yaw_neg): unknown key(s) ['rate_deg_s'] (line {line_of(text, 'rate_deg_s')})" in message


def refusal_reading(read, path, text) -> str:
    """What ``read`` refuses of ``text`` written to ``path``."""
    path.write_text(text)
    with pytest.raises(TelemetryError) as refused:
        read(path)
    return str(refused.value)


def test_a_scenario_schema_violation_names_the_file_key_path_and_line(tmp_path):
    text = (DATA / "tiny.yaml").read_text().replace('{id: roll_pos,  axis: roll,  direction: "+"}',
                                                    '{id: roll_pos,  axis: roll,  direction: "+", rate_deg: 1}')
    path = tmp_path / "scenario.yaml"
    assert refusal_reading(scenario.load_scenario, path, text).startswith(
        f"{path}: maneuvers[2]: unknown key(s) ['rate_deg'] (line {line_of(text, 'rate_deg: 1')})")


def test_a_scenario_base_that_loops_is_refused(tmp_path):
    (tmp_path / "a.yaml").write_text("base: b.yaml\n")
    (tmp_path / "b.yaml").write_text("base: a.yaml\n")
    with pytest.raises(TelemetryError, match=r"a\.yaml is a base of itself"):
        scenario.load_scenario(tmp_path / "a.yaml")


def test_a_mapping_schema_violation_names_the_file_key_path_and_line(tmp_path):
    text = (importer.mapping_path("repoimu")).read_text().replace("order: wxyz", "order: zyxw")
    path = tmp_path / "mine.yaml"
    assert refusal_reading(importer.read_mapping, path, text).startswith(
        f"{path}: reference.order: must be xyzw (scalar last) or wxyz (scalar first), got 'zyxw' "
        f"(line {line_of(text, 'zyxw')})")


def test_a_mapping_with_a_gyro_column_without_an_axis_is_refused(tmp_path):
    mapping = importer.read_mapping("repoimu")
    del mapping["gyro"]["axes"]["gyro_z"]
    (tmp_path / "mine.yaml").write_text(yaml.safe_dump(mapping))
    with pytest.raises(TelemetryError, match=r"gyro \(line \d+\): gyro\.columns and gyro\.axes must name the same "
                                             r"channels; \['gyro_z'\]"):
        importer.read_mapping(tmp_path / "mine.yaml")


def test_a_config_with_an_alias_is_refused_by_plan(tmp_path):
    path = tmp_path / "config.yaml"
    path.write_text((ROOT / "config" / "config.yaml").read_text() + "extra: &x 1\n")
    with pytest.raises(TelemetryError, match=r"config\.yaml: line \d+: an anchor \(&x\)"):
        plan.read_config(path)


def free_named(text):
    """The campaign with its channels named gyro_<axis><k>, as an importer would name them."""
    names = {"dtg1_roll": "gyro_r1", "dtg3_roll": "gyro_r2", "dtg1_pitch": "gyro_p1", "dtg2_pitch": "gyro_p2",
             "dtg2_yaw": "gyro_y1", "dtg3_yaw": "gyro_y2"}
    for old, new in names.items():
        text = text.replace(old, new)
    return text.replace("    dtg: 1\n", "").replace("    dtg: 2\n", "").replace("    dtg: 3\n", "")


def test_in_loop_works_for_channels_with_free_names(tiny, tmp_path):
    directory = tmp_path / "campaign"
    shutil.copytree(tiny[0], directory)
    for name in ("campaign.yaml", "gyro.csv"):
        (directory / name).write_text(free_named((directory / name).read_text()))
    campaign = telemetry.read_campaign(directory)
    assert campaign.maneuvers[0].in_loop == ("gyro_r2", "gyro_p1", "gyro_y1")
    assert all(c.dtg is None for c in campaign.channels)


def test_in_loop_with_two_channels_on_one_axis_is_refused_naming_their_axes(tmp_path, meta_text):
    text = free_named(meta_text).replace("  - gyro_p1\n", "  - gyro_r1\n", 1)
    message = refusal(campaign_dir(tmp_path, text))
    assert "maneuvers[0] (yaw_pos).in_loop: needs one channel per axis" in message
    assert "(axes ['roll', 'roll', 'yaw'])" in message


def test_a_non_unit_boresight_is_refused_and_a_rounded_one_normalised(tmp_path, meta_text):
    text = meta_text.replace("  - 0.954\n", "  - 1.954\n")
    message = refusal(campaign_dir(tmp_path, text))
    assert f"star_tracker.boresight_body (line {line_of(text, '  - 0.3')}): must be a unit vector in body axes; " \
           f"[0.3, 0.0, 1.954] has norm {(0.3 ** 2 + 1.954 ** 2) ** 0.5:.6g}, off 1 by more than 0.001" in message
    meta = read_meta(campaign_dir(tmp_path, meta_text, name="rounded"))  # [0.3, 0, 0.954]: norm 1.00006
    assert abs(sum(v * v for v in meta["star_tracker"]["boresight_body"]) - 1.0) < 1e-12


@pytest.mark.parametrize("kind", sorted(yamlfile.SCHEMAS))
def test_each_schema_is_a_valid_draft_2020_12_schema(kind):
    jsonschema.Draft202012Validator.check_schema(yamlfile.schema(kind))


def repo_yaml(*patterns):
    return sorted(p for pattern in patterns for p in ROOT.glob(pattern))


SCENARIOS = [p for p in repo_yaml("config/scenarios/*.yaml", "tests/data/*.yaml", "studies/data/*.yaml", "examples/*/*.yaml")
             if {"maneuvers", "base"} & set(yaml.safe_load(p.read_text()))]


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_scenario_in_the_repo_passes_its_schema(path):
    yamlfile.check_schema(yamlfile.read_yaml(path), "scenario")
    assert scenario.load_scenario(path)["maneuvers"]


def test_the_shipped_mapping_and_a_written_campaign_pass_their_schemas(tiny):
    yamlfile.check_schema(yamlfile.read_yaml(importer.mapping_path("repoimu")), "mapping")
    yamlfile.check_schema(yamlfile.read_yaml(tiny[0] / "campaign.yaml"), "campaign", label_ids=True)


@pytest.mark.parametrize("path", repo_yaml("config/*.yaml", "examples/*/*.yaml", "tests/data/*.yaml"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_config_in_the_repo_passes_the_loader(path):
    assert isinstance(yamlfile.load_yaml(path), dict)


def test_the_schemas_ship_as_json_beside_the_package():
    for name in yamlfile.SCHEMAS.values():
        assert json.loads((Path(yamlfile.__file__).parent / "schemas" / name).read_text())["$schema"].endswith("2020-12/schema")


def test_the_reference_clock_and_jitter_keys_are_read_and_a_negative_clock_refused(tmp_path, meta_text):
    """``star_tracker: gm_clock_s_per_rad`` and ``st_jitter_ms``, as docs/interface.md section 3 shows them,
    are read; a clock below 0 is refused naming the key."""
    text = meta_text.replace("star_tracker:\n", "star_tracker:\n  gm_clock_s_per_rad: 3000\n  st_jitter_ms: 2\n", 1)
    meta = read_meta(campaign_dir(tmp_path, text))
    assert meta["star_tracker"]["gm_clock_s_per_rad"] == 3000 and meta["star_tracker"]["st_jitter_ms"] == 2
    bad = meta_text.replace("star_tracker:\n", "star_tracker:\n  gm_clock_s_per_rad: -1\n", 1)
    assert "star_tracker.gm_clock_s_per_rad" in refusal(campaign_dir(tmp_path, bad, name="bad"))


def test_the_reference_clock_may_be_left_to_the_data_and_another_word_is_refused(tmp_path, meta_text):
    """``gm_clock_s_per_rad: auto`` asks the preprocessing to choose it (`gyrocal.inference.clock`); any other
    word is refused naming the key, the value and what it takes."""
    text = meta_text.replace("star_tracker:\n", "star_tracker:\n  gm_clock_s_per_rad: auto\n", 1)
    assert read_meta(campaign_dir(tmp_path, text))["star_tracker"]["gm_clock_s_per_rad"] == "auto"
    bad = meta_text.replace("star_tracker:\n", "star_tracker:\n  gm_clock_s_per_rad: automatic\n", 1)
    said = refusal(campaign_dir(tmp_path, bad, name="bad"))
    assert "star_tracker.gm_clock_s_per_rad" in said and "or auto" in said and "'automatic' (line" in said


def test_what_the_stated_reference_noise_is_may_be_said_and_needs_both_sigmas(tmp_path, meta_text):
    """``star_tracker: sigma_is: white`` (what ``gyrocal import`` writes for a noise measured at rest) is read
    beside both sigmas; another word is refused naming the key and what it takes, and ``sigma_is`` without
    the sigmas it speaks of is refused (the config's defaults are a star tracker's total)."""
    assert "sigma_cross_arcsec" in meta_text and "sigma_about_arcsec" in meta_text  # the tiny campaign states both
    text = meta_text.replace("star_tracker:\n", "star_tracker:\n  sigma_is: white\n", 1)
    assert read_meta(campaign_dir(tmp_path, text))["star_tracker"]["sigma_is"] == "white"
    bad = meta_text.replace("star_tracker:\n", "star_tracker:\n  sigma_is: rest\n", 1)
    said = refusal(campaign_dir(tmp_path, bad, name="bad"))
    assert "star_tracker.sigma_is" in said and "total" in said and "white" in said
    kept = [line for line in text.splitlines() if "sigma_about_arcsec" not in line]
    assert "needs both beside it" in refusal(campaign_dir(tmp_path, "\n".join(kept) + "\n", name="alone"))
