"""Writing results whole or not at all: each file is written beside its place under a
temporary name and renamed into place only when complete."""

import json
import math
import os
import shutil
from contextlib import contextmanager
from pathlib import Path

from gyrocal.errors import OutputError

__all__ = ["atomic", "atomic_dir", "strict", "write_csv", "write_json", "write_text", "write_with"]


@contextmanager
def atomic(path):
    """Yield a temporary path beside ``path``; rename it into place on success only. A write that
    fails (a full disk: ENOSPC) removes the temporary and raises `OutputError` naming ``path`` and
    the cause."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        yield tmp
        os.replace(tmp, path)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(path, exc) from exc
    finally:
        _remove(tmp)


def _remove(tmp):
    """Remove a temporary file (or the link in its place), whatever it holds."""
    try:
        if tmp.exists() or tmp.is_symlink():
            tmp.unlink()
    except OSError:
        pass


@contextmanager
def atomic_dir(path):
    """Yield an empty temporary directory beside ``path``; on success it replaces ``path`` (and
    whatever was there) as a whole, so a failed step leaves no half-written directory."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        tmp.mkdir()
        yield tmp
        shutil.rmtree(path, ignore_errors=True)
        os.replace(tmp, path)
    except OutputError:
        raise
    except OSError as exc:
        raise OutputError(path, exc) from exc
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
