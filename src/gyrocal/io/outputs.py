"""Writing results whole or not at all: each file is written beside its place under a
temporary name and renamed into place only when complete."""

import json
import math
import os
import shutil
from contextlib import contextmanager
from pathlib import Path

__all__ = ["OUTPUT_SCHEMAS", "atomic", "atomic_dir", "output_errors", "strict", "write_csv", "write_json",
           "write_text", "write_with"]

OUTPUT_SCHEMAS = {"verdict.json": "verdict", "diagnostics.json": "diagnostics", "sampler.json": "sampler",
                  "refused.json": "refusal"}
"""The results with a JSON Schema (``gyrocal/io/schemas/<kind>.schema.json``), by file name: their kind."""


@contextmanager
def atomic(path):
    """Yield a temporary path beside ``path``; rename it into place on success only."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


@contextmanager
def atomic_dir(path):
    """Yield an empty temporary directory beside ``path``; on success it replaces ``path`` (and
    whatever was there) as a whole, so a failed step leaves no half-written directory."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    try:
        yield tmp
        shutil.rmtree(path, ignore_errors=True)
        os.replace(tmp, path)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def strict(obj):
    """``obj`` with every non-finite number as ``None``: JSON has no NaN or Infinity, and a strict
    parser (jq, a browser) refuses them; ``null`` says "no value" in JSON's own terms."""
    if isinstance(obj, dict):
        return {k: strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(v) for v in obj]
    if hasattr(obj, "tolist"):
        return strict(obj.tolist())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_json(obj, path):
    """Strict JSON (`strict`), written whole or not at all."""
    with atomic(path) as tmp:
        tmp.write_text(json.dumps(strict(obj), indent=2, sort_keys=False, default=float, allow_nan=False))


def write_csv(frame, path):
    with atomic(path) as tmp:
        frame.to_csv(tmp, index=False)


def write_text(text: str, path):
    with atomic(path) as tmp:
        tmp.write_text(text)


def write_with(save, path):
    """Write through ``save(handle)`` (e.g. an object's ``save`` method or a figure's)."""
    with atomic(path) as tmp, open(tmp, "wb") as handle:
        save(handle)


def output_errors(doc, kind: str) -> list:
    """What in ``doc`` (a result read back: ``verdict.json``, ``diagnostics.json``, ``sampler.json``,
    ``refused.json``) its schema refuses (`OUTPUT_SCHEMAS`), each as ``<key path>: <message>``; empty
    where it conforms. A script that reads results may check them so."""
    from gyrocal.io.yamlfile import _validator

    return [f"{'.'.join(map(str, e.absolute_path)) or '(top)'}: {e.message}"
            for e in sorted(_validator(kind).iter_errors(doc), key=lambda e: list(map(str, e.absolute_path)))]
