"""rbfmu run and sweep options with hostile values: refused before the build, or computed right (issue 39, items 9, 10).

No test here builds an FMU: every refusal comes before the build, and the sweep's axis
values are computed by the option parser alone.
"""

from __future__ import annotations

import warnings

import pytest

import fmu.cli as cli
from fmu.cli import main
from fmu.sweep.spec import parse_param


def _no_build(*args, **kwargs):
    raise AssertionError("the FMU was built before the option was checked")


@pytest.mark.parametrize("path", ["/proc/x.csv", "/proc/self/none/x.csv"])
def test_unwritable_csv_is_refused_before_the_build(monkeypatch, capsys, path):
    """Item 9. Before: built and ran (7-18 s), then a raw "[Errno 2] No such file or directory"."""
    monkeypatch.setattr(cli, "ensure_fmu", _no_build)
    assert main(["run", "dual_spin", "--csv", path]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("rbfmu: error: ") and "\n" not in err, err
    assert f"--csv {path}:" in err and ("cannot be written" in err or "does not exist" in err), err


def test_writable_csv_check_leaves_no_file(tmp_path, monkeypatch):
    """The check opens the file to know it is writable; a file it created is removed again."""
    monkeypatch.setattr(cli, "ensure_fmu", _no_build)
    target = tmp_path / "out.csv"
    with pytest.raises(AssertionError, match="built before"):
        main(["run", "dual_spin", "--csv", str(target), "--build-dir", str(tmp_path / "b")])
    assert not target.exists()


@pytest.mark.parametrize(
    "text, expected",
    [
        ("Omega_wheel=-1e308:1e308:3", (-1e308, 0.0, 1e308)),
        ("Omega_wheel=-1.5e308:1.5e308:4", (-1.5e308, -0.5e308, 0.5e308, 1.5e308)),
        ("w_body[3]=50:200:4", (50.0, 100.0, 150.0, 200.0)),
    ],
)
def test_range_whose_width_overflows_gives_the_right_values(text, expected):
    """Item 10. Before: numpy RuntimeWarnings, then "value must be finite, got nan"
    (np.linspace's step (stop - start)/(n - 1) overflowed). Now computed as
    start (1 - t) + stop t: each value within 2 ulp of the exact one, no warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        values = parse_param(text).values
    assert len(values) == len(expected)
    for v, e in zip(values, expected):
        assert abs(v - e) <= 4.5e-16 * max(abs(e), 1.0), (v, e)
