"""What `rbfmu sweep` refuses and warns about, found by an audit of its command line.

A negative seed, draws that overflow, empty option values, --build-dir with an .fmu, a
--plot path that cannot be written, a log colour scale with nothing to show, an FMI 2.0
FMU; swept values in the wrong unit are warned.

Before these fixes each one ended in a Python traceback, ran with the setting silently
ignored, ran every run before failing, or printed something untrue. Each is now one line
`rbfmu: error: ...` (exit status 2) naming the value and what is allowed, before any run
where it can be known then (the runs are replaced by a stub that records being called).
"""

from __future__ import annotations

import sys
import warnings

import numpy as np
import pandas as pd
import pytest

from fmu.cli import main
from fmu.sweep import spec
from fmu.sweep.api import sample_runs, sweep
from fmu.sweep.results import plot_map
from modelsrc.errors import ModelInputError


def _one_line(capsys, *args: str) -> str:
    code = main(list(args))
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("rbfmu: error: ") and err.count("\n") == 1, (code, err)
    return err.strip()


@pytest.fixture
def no_runs(monkeypatch, tmp_path) -> list[object]:
    """The sweep's runs replaced by a stub that records a call; the current directory is
    tmp_path (empty), so that anything written there shows."""
    ran: list[object] = []
    monkeypatch.setattr("fmu.sweep.cli.sweep", lambda *a, **k: ran.append(a))
    monkeypatch.chdir(tmp_path)
    return ran


GRID = ["sweep", "thrown_racket", "--param", "mass=0.3:0.4:2", "--workers", "0"]


# --- 1: the seed --------------------------------------------------------------------------------


def test_a_negative_seed_is_refused_with_the_allowed_range(capsys, no_runs, tmp_path):
    """Was: ValueError: expected non-negative integer (a traceback from numpy)."""
    err = _one_line(capsys, "sweep", "thrown_racket", "--sample", "mass=uniform(0.3, 0.4)", "--samples", "2",
                    "--seed", "-5", "--workers", "0")  # fmt: skip
    assert "--seed -5: the seed must be a whole number >= 0" in err
    assert no_runs == [] and list(tmp_path.iterdir()) == []
    with pytest.raises(ModelInputError, match=r"seed -1: the seed must be a whole number >= 0"):
        sample_runs({"mass": ("uniform", 0.3, 0.4)}, 2, seed=-1)


# --- 2: draws that overflow ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "text, message",
    [
        ("uniform(-1e308, 1e308)", "uniform(LOW, HIGH) needs HIGH - LOW to be a finite number (at most 1.798e+308)"),
        ("uniform(-1.7e308, 0.5e308)", "0.5e308 - (-1.7e308) overflows"),
        ("normal(0, 1e308)", "normal(MEAN, STD) draws reach MEAN ± 14 STD, which must stay finite"),
        ("normal(1.7e308, 1e307)", "with 1.7e308, 1e307 they overflow"),
        ("normal(-1.7e308, 1e307)", "with -1.7e308, 1e307 they overflow"),
    ],
)
def test_distributions_whose_draws_overflow_are_refused_when_parsed(text, message):
    """Was: OverflowError: high - low range exceeds valid bounds (uniform, a traceback), or
    ±inf draws refused after the build as 'swept variable ...: value must be finite' (normal)."""
    with pytest.raises(ModelInputError) as exc:
        spec.parse_sample(f"w_body[3]={text}")
    assert str(exc.value).startswith(f"--sample 'w_body[3]={text}': ") and message in str(exc.value)


def test_the_widest_accepted_distributions_draw_finite_values():
    """The limits are sound: at them numpy's draws stay finite (the normal's reach bounds its
    standard draws, which stay within ±13.7 from 53-bit uniforms)."""
    big = sys.float_info.max
    for text in (f"uniform({-big / 2!r}, {big / 2!r})", f"normal(0, {big / 14.0001!r})", "loguniform(5e-324, 1e308)"):
        d = spec.parse_sample(f"x={text}")
        assert np.isfinite(d.draw(np.random.default_rng(7), 200_000)).all(), text


def test_an_overflowing_sample_is_refused_on_the_command_line_before_any_run(capsys, no_runs, tmp_path):
    err = _one_line(capsys, "sweep", "thrown_racket", "--sample", "mass=uniform(-1e308,1e308)", "--samples", "2",
                    "--seed", "1", "--workers", "0")  # fmt: skip
    assert "--sample 'mass=uniform(-1e308,1e308)': uniform(LOW, HIGH) needs HIGH - LOW to be a finite" in err
    assert no_runs == [] and list(tmp_path.iterdir()) == []
    with pytest.raises(ModelInputError, match="needs HIGH - LOW to be a finite number"):
        sample_runs({"mass": ("uniform", -1e308, 1e308)}, 2, seed=1)


# --- 3: empty values ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--scheduler", ""], "--scheduler '': empty; give the address of a running dask scheduler"),
        (["--plot", ""], "--plot '': empty; give the map's file name (.png)"),
        (["--plot-figure", "E_kin", "--plot", ""], "--plot '': empty"),
        (["--plot", "m.png", "--plot-axes", ""], "--plot-axes '': empty; give X or X,Y"),
        (["--plot", "m.png", "--plot-figure", " "], "--plot-figure ' ': empty"),
        (["--out", ""], "--out '': empty; give the table's file name (.parquet or .csv)"),
        (["--build-dir", ""], "--build-dir '': empty; give a directory"),
        (["--dashboard", ""], "--dashboard '': empty; give HOST:PORT"),
    ],
    ids=lambda v: " ".join(repr(a) for a in v) if isinstance(v, list) else "",
)
def test_an_empty_value_is_refused_not_taken_as_the_option_left_out(capsys, no_runs, tmp_path, extra, message):
    """Was: --scheduler '' ran locally, --plot '' wrote no map, --plot-axes '' mapped the
    default axes, --build-dir '' built the FMU into the current directory."""
    err = _one_line(capsys, *GRID, *extra)
    assert message in err
    assert no_runs == [] and list(tmp_path.iterdir()) == []  # no table, no map, no FMU


# --- 4: --build-dir with an .fmu ----------------------------------------------------------------


def test_build_dir_with_an_fmu_file_is_refused(capsys, no_runs, tmp_path, fmus):
    """Was: the .fmu was swept and --build-dir ignored (even a file such as /etc/passwd)."""
    (tmp_path / "plain").write_text("a file")
    for build_dir in (str(tmp_path / "plain"), str(tmp_path / "fmus")):
        err = _one_line(capsys, "sweep", str(fmus["thrown_racket"]), "--param", "mass=0.3:0.4:2", "--workers", "0",
                        "--build-dir", build_dir)  # fmt: skip
        assert (
            f"--build-dir {build_dir}: an .fmu file is swept as it is, nothing is built; leave --build-dir out" in err
        )
    assert no_runs == [] and sorted(p.name for p in tmp_path.iterdir()) == ["plain"]


def test_build_dir_that_is_a_file_is_refused_before_the_build(capsys, no_runs, tmp_path):
    (tmp_path / "plain").write_text("a file")
    err = _one_line(capsys, *GRID, "--build-dir", str(tmp_path / "plain"))
    assert f"--build-dir {tmp_path / 'plain'}: is a file; give a directory" in err
    assert no_runs == [] and sorted(p.name for p in tmp_path.iterdir()) == ["plain"]


def test_an_fmu_file_without_build_dir_is_swept(fmus, tmp_path, capsys):
    out = tmp_path / "t.csv"
    assert main(["sweep", str(fmus["thrown_racket"]), "--param", "mass=0.3:0.4:2", "--workers", "0",
                 "--stop-time", "0.01", "--no-progress", "--out", str(out)]) == 0  # fmt: skip
    assert out.exists() and "2 runs of thrown_racket" in capsys.readouterr().out


# --- 5: a log colour scale with values <= 0 -----------------------------------------------------


def _table(values: list[float]) -> pd.DataFrame:
    df = pd.DataFrame({"mass": np.linspace(0.1, 1.0, len(values)), "fig": values, "ok": True})
    df.attrs.update(scene="s", swept=["mass"])
    return df


def _title(df: pd.DataFrame, path, **kw) -> str:
    axes: list = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib's raw UserWarning would fail here
        plot_map(df, "fig", path, decorate=axes.append, **kw)
    return axes[0].get_title()


def test_log_color_counts_the_values_it_cannot_show(tmp_path):
    """Was: the title counted only NaN cells; cells <= 0 were grey (or missing) unsaid."""
    title = _title(_table([1.0, 0.0, -2.0, np.nan, 3.0]), tmp_path / "a.png", log_color=True)
    assert "NaN (1 runs), <= 0 off the log scale (2 runs)" in title
    df = _table([1.0, 0.0, -2.0, np.nan, 3.0])
    df = pd.concat([df.assign(y=1.0), df.assign(y=2.0)], ignore_index=True)  # a grid of two: a heat map
    title = _title(df, tmp_path / "b.png", x="mass", y="y", log_color=True)
    assert "grey: NaN (2 runs), <= 0 off the log scale (4 runs)" in title
    title = _title(_table([1.0, 0.0, np.nan]), tmp_path / "c.png")  # a linear scale shows 0
    assert "not drawn: NaN (1 runs)" in title and "<= 0" not in title


def test_log_color_with_no_positive_value_is_refused_with_the_reason(tmp_path):
    """Was: matplotlib's 'UserWarning: Data has no positive values', an empty map, and a
    title saying 'grey: NaN (0 runs)'."""
    with pytest.raises(ModelInputError) as exc:
        _title(_table([0.0, -1.0, np.nan]), tmp_path / "a.png", log_color=True)
    assert str(exc.value) == (
        "plot: a log colour scale (--log-color) shows values > 0; fig has none in the 3 runs (2 <= 0, 1 NaN): "
        "map it without --log-color"
    )
    assert not (tmp_path / "a.png").exists()


def test_rbfmu_sweep_log_color_with_no_positive_value_keeps_the_table_and_names_the_option(fmus, tmp_path, capsys):
    """Only the runs tell whether a figure has a value > 0: the table is written, the map refused."""
    out, png = tmp_path / "t.csv", tmp_path / "m.png"
    code = main(["sweep", str(fmus["thrown_racket"]), "--param", "mass=0.3:0.4:2", "--set", "w_body[1]=-1",
                 "--workers", "0", "--stop-time", "0.01", "--no-progress", "--out", str(out), "--plot", str(png),
                 "--log-color", "--plot-figure", "end(w_body[1])"])  # fmt: skip
    std = capsys.readouterr()
    assert code == 2 and f"table: {out}" in std.out and std.err.count("\n") == 1, std
    assert std.err.startswith("rbfmu: error: plot: a log colour scale (--log-color) shows values > 0; end(w_body[1]) ")
    assert "has none in the 2 runs (2 <= 0, 0 NaN): map it without --log-color" in std.err
    assert out.exists() and not png.exists()


# --- 6: the --plot path -------------------------------------------------------------------------


@pytest.mark.parametrize("where, message", [("plain/x.png", "plain is a file, not a directory"),
                                            ("no/such/x.png", "the directory {d}/no/such does not exist")])  # fmt: skip
def test_a_plot_path_that_cannot_be_written_is_refused_before_any_run(capsys, no_runs, tmp_path, where, message):
    """Was: every run, the table written, then `rbfmu: error: [Errno 17] File exists: ...`
    without naming --plot."""
    (tmp_path / "plain").write_text("a file")
    plot = tmp_path / where
    err = _one_line(capsys, *GRID, "--plot", str(plot), "--out", str(tmp_path / "t.csv"))
    assert err.startswith(f"rbfmu: error: --plot {plot}: ") and message.format(d=tmp_path) in err
    assert no_runs == [] and sorted(p.name for p in tmp_path.iterdir()) == ["plain"]


# --- 7: an FMI 2.0 FMU --------------------------------------------------------------------------


def test_an_fmi2_fmu_is_refused_for_its_version(capsys, monkeypatch, tmp_path, fmi2_fmus):
    """Was: 'not built from a shipped scene by this rbfmu; pass the scene it was built from
    (scene=...)': untrue, and scene= has no command-line flag."""
    monkeypatch.chdir(tmp_path)
    path = fmi2_fmus["heavy_top"]
    errors = [_one_line(capsys, "sweep", str(path), "--param", "mass=1:2:2", "--workers", "0")]
    for scene in (None, "heavy_top"):
        with pytest.raises(ModelInputError) as exc:
            sweep(path, {"mass": [1.0]}, scene=scene, workers=0)
        errors.append(str(exc.value))
    for err in errors:
        assert f"{path}: sweeps run FMI 3.0 FMUs, this one is FMI 2.0; build its scene as FMI 3.0 " in err
        assert "(rbfmu build SCENE, without --fmi-version 2) or sweep the scene itself" in err
        assert "scene=" not in err and "shipped scene" not in err
    assert list(tmp_path.iterdir()) == []  # no table (nor its temporary file)


def test_swept_values_in_the_wrong_unit_are_warned_once_per_column():
    # rbfmu run --set orbit_angle=30 warned; --param 'orbit_angle=30,60' and --sample of n_orbit did not
    import pandas as pd

    from fmu.sweep.api import warn_unit_mistakes
    from modelsrc.errors import ModelInputWarning

    runs = pd.DataFrame({"orbit_angle": [0.1, 30.0, 60.0], "n_orbit": [1e-3, 1.1e-3, 1.2e-3], "w_body[1]": [1, 2, 3]})
    with pytest.warns(ModelInputWarning) as caught:
        warn_unit_mistakes(runs)
    texts = [str(w.message) for w in caught]
    assert len(texts) == 1 and texts[0].startswith("--param/--sample orbit_angle (its largest value) = 60 rad")
    with pytest.warns(ModelInputWarning, match="n_orbit .* = 5677 rad/s is an orbital period"):
        warn_unit_mistakes(pd.DataFrame({"n_orbit": [5677.0, 1.0e-3]}))


def test_the_api_refuses_a_build_dir_with_an_fmu(fmus, tmp_path):
    # the command line refused it; fmu.sweep.sweep ignored it without a word
    from fmu.sweep.api import sweep

    with pytest.raises(ModelInputError, match=r"an \.fmu archive is swept as it is, nothing is built"):
        sweep(fmus["torque_driven"], {"w_body[3]": [1.0]}, build_dir=tmp_path / "b", workers=0)
    assert not (tmp_path / "b").exists()
