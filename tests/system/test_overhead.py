"""`rbfmu bench --master` (fmu.system.overhead): the master runs it counts, the ratio and the verdict it prints."""

from __future__ import annotations

import pytest

from fmu.cli import main
from fmu.system.build import build_system
from fmu.system.overhead import MasterCost, print_table, run_steps


def test_the_probe_runs_the_slew_in_both_masters(tmp_path, system_build_dir):
    # what callgrind counts: n steps in one call, and the 0-step run whose count is subtracted
    archive = str(build_system("slew", tmp_path, system_build_dir))
    for master in ("ecos", "libcosim"):
        zero, twenty = run_steps(archive, master, 0), run_steps(archive, master, 20)
        assert 0.0 <= zero < twenty, (master, zero, twenty)


def test_the_verdict_is_the_worst_ecos_ratio(capsys):
    rows = [MasterCost("slew", "ecos", 400, 3000.0, 2000.0, 5.0), MasterCost("slew", "libcosim", 400, 9e4, 2e3, 9.0)]
    print_table(rows)
    out = capsys.readouterr().out
    assert "worst 1.50: met" in out  # libcosim's 45x is shown, not judged: the target is ECOS's
    print_table([*rows, MasterCost("quadrotor_hover", "ecos", 1000, 3100.0, 2000.0, 5.0)])
    assert "worst 1.55: NOT met" in capsys.readouterr().out
    assert MasterCost("s", "ecos", 1, None, 10.0, 1.0).ratio is None


def test_master_and_linear_are_exclusive(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["bench", "--master", "--linear"])
    assert exc.value.code == 2 and "not allowed with" in capsys.readouterr().err
