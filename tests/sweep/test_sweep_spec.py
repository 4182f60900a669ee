"""What a sweep runs (grids, samples, figures) and the bad input `rbfmu sweep` refuses with one line."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from fmu.cli import main
from fmu.sweep import sample_runs, spec
from fmu.sweep.figures import Figure, first_crossing, parse_figure
from modelsrc.errors import ModelInputError


def test_param_syntax():
    a = spec.parse_param("w_body[3]=50:200:4")
    assert a.name == "w_body[3]" and a.values == (50.0, 100.0, 150.0, 200.0) and not a.log
    b = spec.parse_param("h_max=1e-5:1e-3:3:log")
    assert b.log and np.allclose(b.values, [1e-5, 1e-4, 1e-3], rtol=1e-14, atol=0)
    assert spec.parse_param("mass=0.1, 0.5,2").values == (0.1, 0.5, 2.0)
    assert spec.parse_param("method=rk4,gauss4").values == ("rk4", "gauss4")
    assert spec.parse_param("r_cm[3]=0.04:0.04:1").values == (0.04,)


def test_grid_is_the_cartesian_product_first_axis_slowest():
    runs = spec.grid([spec.Axis("a", (1.0, 2.0)), spec.Axis("b", (10.0, 20.0, 30.0))])
    assert runs.to_numpy().tolist() == [[1, 10], [1, 20], [1, 30], [2, 10], [2, 20], [2, 30]]
    both = spec.plan([spec.Axis("a", (1.0, 2.0))], [spec.Distribution("c", "uniform", 0.0, 1.0)], 3, seed=5)
    assert len(both) == 6 and list(both.columns) == ["a", "c"]
    # common random numbers: the same draws at every grid point
    assert np.array_equal(both["c"].to_numpy()[:3], both["c"].to_numpy()[3:])


def test_samples_are_reproducible_and_follow_their_distributions():
    dists = [
        spec.parse_sample("x=normal(2.0, 0.5)"),
        spec.parse_sample("y=uniform(-1, 3)"),
        spec.parse_sample("z=loguniform(1e-3, 1e3)"),
    ]
    n = 20000
    a, b, c = spec.samples(dists, n, 7), spec.samples(dists, n, 7), spec.samples(dists, n, 8)
    pd.testing.assert_frame_equal(a, b)
    assert not np.array_equal(a["x"], c["x"])
    # moments within 5 standard errors (a false failure has probability ~6e-7 per check)
    assert abs(a["x"].mean() - 2.0) < 5 * 0.5 / math.sqrt(n)
    assert abs(a["x"].std() - 0.5) < 5 * 0.5 / math.sqrt(2 * n)
    assert a["y"].between(-1, 3).all() and abs(a["y"].mean() - 1.0) < 5 * (4 / math.sqrt(12)) / math.sqrt(n)
    logz = np.log10(a["z"])
    assert logz.between(-3, 3).all() and abs(logz.mean()) < 5 * (6 / math.sqrt(12)) / math.sqrt(n)


def test_sample_runs_of_the_python_api_record_their_seed():
    a = sample_runs({"mass": ("normal", np.float64(0.5), 0.01), "h_max": ("loguniform", 1e-5, 1e-3)}, 50, seed=3)
    b = sample_runs({"mass": ("normal", 0.5, 0.01), "h_max": ("loguniform", 1e-5, 1e-3)}, 50, seed=3)
    pd.testing.assert_frame_equal(a, b)
    assert a.attrs["seed"] == 3 and isinstance(sample_runs({"mass": ("uniform", 0, 1)}, 2).attrs["seed"], int)


def test_figures_parse_to_canonical_columns():
    assert parse_figure("max( euler_zxz[2] )") == Figure("max", "euler_zxz[2]")
    assert parse_figure("E_kin").column == "end(E_kin)"
    assert parse_figure("cross(w_body[2], 0)").column == "cross(w_body[2], 0)"
    assert parse_figure("cross(euler_zxz[2],0.3)") == Figure("cross", "euler_zxz[2]", 0.3)
    with pytest.raises(ModelInputError, match="unknown function 'mean'"):
        parse_figure("mean(E_kin)")
    with pytest.raises(ModelInputError, match="cross takes an output and a level"):
        parse_figure("cross(w_body[2])")


def test_first_crossing_interpolates_between_samples():
    t = np.linspace(0.0, 1.0, 11)
    assert first_crossing(t, 1.0 - 2.0 * t, 0.0) == pytest.approx(0.5, abs=1e-15)  # linear: exact
    assert first_crossing(t, 0.1 + t, 0.55) == pytest.approx(0.45, abs=1e-15)  # from below
    assert math.isnan(first_crossing(t, 1.0 + t, 0.0))  # never
    assert first_crossing(t, t, 0.0) == 0.0  # starts at the level
    y = np.sin(2 * np.pi * 3 * t + 0.3)
    assert first_crossing(t, y, 0.0) < 1 / 6  # the first of the zeros


BAD_INPUT = [
    (
        ["--param", "w_body[9]=1:2:3"],
        "unknown variable 'w_body[9]'; did you mean 'w_body[3]' or 'w_body[2]' or 'w_body[1]'? Settable",
    ),
    (["--param", "w_bdy[3]=1:2:3"], "unknown variable 'w_bdy[3]'; did you mean 'w_body[3]'? Settable: q[1..4], w_"),
    (["--param", "E_total=1:2:3"], "variable 'E_total' is not settable; settable: q[1..4], w_body[1..3], I_p"),
    (["--sample", "mas=normal(0.5, 0.1)", "--samples", "4"], "unknown variable 'mas'; did you mean 'mass'?"),
    (["--param", "w_body[3]=100:100:5"], "empty range: START = STOP = 100 with N = 5 > 1"),
    (["--param", "w_body[3]=100:200:0"], "N must be a whole number >= 1, got 0"),
    (["--param", "w_body[3]=100:200:-2"], "N must be a whole number >= 1, got -2"),
    (["--param", "w_body[3]=100:200:2.5"], "N must be a whole number >= 1, got 2.5"),
    (["--param", "w_body[3]=a:200:3"], "START 'a' is not a number"),
    (["--param", "h_max=0:1e-3:3:log"], "a log range needs START > 0"),
    (["--param", "w_body[3]="], "expected NAME=START:STOP:N"),
    (["--param", "mass=1:2:2", "--param", "mass=3:4:2"], "variable mass is swept twice"),
    (["--param", "method=rk4,nosuch"], "method 'nosuch' is not compiled into this FMU"),
    (["--sample", "mass=gauss(0.5, 0.1)", "--samples", "4"], "unknown distribution 'gauss'"),
    (["--sample", "mass=normal(0.5, 0)", "--samples", "4"], "normal(MEAN, STD) needs STD > 0"),
    (["--sample", "mass=uniform(2, 1)", "--samples", "4"], "uniform(LOW, HIGH) needs LOW < HIGH"),
    (["--sample", "mass=loguniform(0, 1)", "--samples", "4"], "loguniform(LOW, HIGH) needs LOW > 0"),
    (["--sample", "mass=normal(0.5)", "--samples", "4"], "normal takes two numbers"),
    (["--sample", "mass=normal(0.5, 0.1)", "--samples", "0"], "--samples must be >= 1, got 0"),
    (["--sample", "mass=normal(0.5, 0.1)"], "--sample needs --samples N"),
    ([], "nothing to sweep"),
    (["--param", "mass=1:2:2", "--record", "mean(E_total)"], "unknown function 'mean'"),
    (
        ["--param", "mass=1:2:2", "--record", "max(mass)"],
        "variable 'mass' is not an output of this FMU; outputs: q[1..4]",
    ),
    (
        ["--param", "mass=1:2:2", "--record", "max(E_totl)"],
        "unknown variable 'E_totl'; did you mean 'E_total'? Outputs",
    ),
    (["--param", "mass=1:2:2", "--set", "mass=3"], "mass is also swept"),
    (["--param", "mass=1:2:2", "--set", "g[3]=nan"], "--set 'g[3]=nan': value must be finite, got nan"),
    (["--param", "mass=1:2:2", "--set", "g[3]="], "--set 'g[3]=': expected NAME=VALUE"),
    (["--param", "mass=1:2:2", "--out", "table.xlsx"], "the table is written as .parquet or .csv"),
    (["--param", "mass=1:2:2", "--workers", "-1"], "--workers must be >= 0"),
    (["--param", "mass=1:2:2", "--stop-time", "-1"], "stop_time must be a finite number > 0, got -1"),
    (["--param", "mass=1:2:2", "--plot", "m.png", "--plot-axes", "g[3]"], "the map is over one or two swept"),
    (["--param", "mass=1:2:1001", "--param", "g[3]=-9:-10:10001"], "the sweep would have 10011001 runs; at most"),
    (["--param", "mass=1:2:2", "--scheduler", "nonsense"], "--scheduler nonsense: cannot connect to a dask scheduler"),
]


@pytest.mark.parametrize("args,message", BAD_INPUT, ids=[m for _, m in BAD_INPUT])
def test_bad_input_is_one_line_naming_the_problem(args, message, fmus, build_dir, tmp_path, capsys):
    out = tmp_path / "sweep.parquet"
    argv = ["sweep", "heavy_top", "--workers", "0", "--build-dir", str(build_dir), "--out", str(out), *args]
    if "--out" in args:
        argv[argv.index("--out") : argv.index("--out") + 2] = []
    if "--workers" in args or "--scheduler" in args:
        argv[argv.index("--workers") : argv.index("--workers") + 2] = []
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rbfmu: error: "), err
    assert message in err[0], err[0]
    assert not out.exists()  # nothing ran


@pytest.mark.parametrize(
    "column, message",
    [
        ([1.0, math.nan], "swept variable mass: value must be finite, got nan"),
        ([1.0, "heavy"], "swept variable mass: value 'heavy' is not a number"),
    ],
)
def test_a_swept_column_is_checked_by_the_one_number_check(column, message):
    # a table of runs given through the Python API is checked like --set and --param values
    variables = spec.Variables({"mass": spec.PARAMETER}, ("E_total",), {"rk4": 1})
    with pytest.raises(ModelInputError) as exc:
        spec.check_runs(pd.DataFrame({"mass": column}), variables)
    assert str(exc.value) == message
    assert spec.check_runs(pd.DataFrame({"mass": [1.0, "2.5"]}), variables)["mass"].tolist() == [1.0, 2.5]
