"""Rules ``study_chunk`` and ``study_summary`` of the validation study (workflow/study/Snakefile)."""

import json
from pathlib import Path

from gyrocal.io.outputs import atomic, write_csv, write_json, write_with
from gyrocal.study import campaign as study

__all__ = ["read_records", "run_chunk", "summarize"]


def run_chunk(scenario_path, cfg, study_cfg, group, indices, out_json):
    """Simulate and calibrate the campaigns ``indices`` of ``group``; their records, written whole."""
    magnitudes = [0.0] if group == "clean" else study_cfg["effects"][group]["magnitudes"]
    records = [study.run(scenario_path, cfg, study_cfg, i, group,
                         magnitudes[i // study_cfg["repeats"]] if group != "clean" else 0.0) for i in indices]
    write_json(records, out_json)


def read_records(paths) -> list:
    return [r for p in paths for r in json.loads(Path(p).read_text())]


def summarize(record_paths, scenario_path, cfg, study_cfg, out_dir):
    """Every table and figure of the study into ``out_dir`` (docs/validation.md lists them)."""
    from gyrocal.planning import plan
    from gyrocal.report import figures as plots
    from gyrocal.study import figures as validationplots
    from gyrocal.study import tables as validation
    records = read_records(record_paths)
    params, models = validation.parameter_table(records), validation.model_table(records)
    out_dir = Path(out_dir)
    planned = plan.plan(plan.read_scenario(scenario_path), cfg)
    predicted = planned.table()
    predicted["label"] = predicted["channel"] + "." + predicted["parameter"]
    detectable = {}  # each effect's 90 %-detection magnitude, planned on the scenario its campaigns fly
    for path in {e.get("scenario", str(scenario_path)) for e in study_cfg["effects"].values()}:
        table = (planned if path == str(scenario_path) else plan.plan(plan.read_scenario(path), cfg)).detection
        flown = [name for name, e in study_cfg["effects"].items() if e.get("scenario", str(scenario_path)) == path]
        found = table[table["effect"].isin(flown)].groupby("effect")["detectable_magnitude"].min()
        detectable.update({e: v / study_cfg["effects"][e].get("model_per_simulator_unit", 1.0) for e, v in found.items()})
    accuracy = validation.accuracy(params)
    clean = validation.clean_baseline(params)
    tables = {
        "parameters": params,
        "accuracy": accuracy,
        "coverage": validation.coverage(clean),
        "coverage_per_parameter": validation.coverage(clean, by=["label"]),
        "sbc": validation.sbc(params, models),
        "error_rates": validation.error_rates(models, cfg["diagnostics"]),
        "detection": validation.detection(models, {name: effect.get("signatures", [])
                                                   for name, effect in study_cfg["effects"].items()}),
        "extended_coverage": validation.extended_coverage(params),
        "plan_check": validation.plan_check(params, predicted),
        "campaigns": models,
    }
    for name, table in tables.items():
        write_csv(table, out_dir / f"{name}.csv")
    write_json({"pooled_efficiency": validation.pooled_efficiency(params), "campaigns": len(records)},
               out_dir / "summary.json")
    with atomic(out_dir / "tables.md") as tmp:
        tmp.write_text(validation.markdown(tables))
    figures = {
        "accuracy": validationplots.accuracy_figure(accuracy),
        "coverage": validationplots.coverage_figure(tables["coverage"], tables["coverage_per_parameter"]),
        "sbc": validationplots.sbc_figure(tables["sbc"]),
        "detection": validationplots.detection_figure(tables["detection"], detectable),
    }
    for name, fig in figures.items():
        write_with(lambda handle, fig=fig: plots.save(fig, handle), out_dir / f"{name}.png")
