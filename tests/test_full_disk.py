"""Outputs are written whole or not at all: a write that the disk refuses (ENOSPC, here from the OS
itself: the temporary's name links to /dev/full, whose every write fails with it) leaves no
temporary and no partial file, and says which file and why, not a traceback."""

import errno
import os
from pathlib import Path

import arviz as az
import numpy as np
import pytest

from gyrocal.errors import OutputError
from gyrocal.io.outputs import atomic, write_json
from gyrocal.pipeline import cli

from conftest import DATA

pytestmark = pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full (Linux)")


def full_disk_at(path):
    """The temporary ``atomic`` writes ``path`` through is a link to /dev/full."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.parent.mkdir(parents=True, exist_ok=True)
    os.symlink("/dev/full", tmp)
    return tmp


def test_a_json_write_on_a_full_disk_names_the_file_and_removes_its_temporary(tmp_path):
    path = tmp_path / "verdict.json"
    tmp = full_disk_at(path)
    with pytest.raises(OutputError) as err:
        write_json({"verdict": "GO"}, path)
    assert err.value.errno == errno.ENOSPC
    assert str(err.value) == (f"{path}: could not be written: No space left on device (ENOSPC); nothing was written "
                              "there and its temporary was removed. Free space on its disk, and run again")
    assert not path.exists() and not tmp.is_symlink() and not tmp.exists()


def test_a_posterior_nc_write_on_a_full_disk_leaves_no_partial_file(tmp_path):
    path = tmp_path / "baseline" / "posterior.nc"
    tmp = full_disk_at(path)
    idata = az.from_dict(posterior={"theta": np.zeros((2, 50))})
    with pytest.raises(OutputError) as err, atomic(path) as out:
        idata.to_netcdf(str(out))
    assert str(err.value).startswith(f"{path}: could not be written: ") and "(ENOSPC)" in str(err.value)
    assert not path.exists() and not tmp.is_symlink()


def test_simulate_on_a_full_disk_prints_the_file_and_cause_and_exits_non_zero(tmp_path, capsys):
    full_disk_at(tmp_path / "truth.json")
    code = cli.main(["simulate", str(DATA / "tiny.yaml"), str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{tmp_path / 'truth.json'}: could not be written: No space left on device (ENOSPC)" in err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["campaign"]
