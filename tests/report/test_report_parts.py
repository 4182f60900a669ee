"""The report's parts take effect or are refused, and its page states only what ran.

Covered: the quick error-control part's scenes, a part that would measure nothing, --quick
where it changes nothing, --build-dir for the inputs part, --out that is a file.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from modelsrc.scene import list_scenes, load_scene
from rbcheck.workprecision import forced_inputs
from rbcheck.workprecision.batch import SceneResult
from rbcheck.workprecision.cli import main, nothing_to_measure
from rbcheck.workprecision.config import DEFAULT_SCENES, PARTS, Config
from rbcheck.workprecision.markdown import _jobs_txt, _whole, write_markdown
from rbcheck.workprecision.measurable import has_scipy_reference, measurable_scenes
from rbcheck.workprecision.tolerance import tolerance_scenes


def test_quick_and_short_error_control_parts_take_only_the_scenes_they_can_measure():
    # `rbfmu report --quick` gave the part all 16 default scenes, and it failed after ~20 s on
    # reaction_wheel_slew ("its reference never turns"): quadrotor and reaction_wheel_slew start at rest
    full = tolerance_scenes(Config())
    assert {"reaction_wheel_slew", "quadrotor"} & set(DEFAULT_SCENES)
    assert not {"reaction_wheel_slew", "quadrotor"} & set(full)
    assert full == tuple(s for s in list_scenes() if has_scipy_reference(load_scene(s)))
    quick, short = Config.quick(DEFAULT_SCENES), Config.short(DEFAULT_SCENES)
    # the full report's rule on the same scenes (the default scenes are the shipped ones)
    assert set(tolerance_scenes(quick)) == set(full) == set(tolerance_scenes(short))
    assert tolerance_scenes(quick) == measurable_scenes(DEFAULT_SCENES)
    assert Config.quick().tol_scenes == ("symmetric_free",)
    # none it can measure is none, not every shipped scene; rbfmu report refuses such a part
    only_slew = Config.quick(("reaction_wheel_slew",))
    assert tolerance_scenes(only_slew) == ()
    assert "tolerance" in nothing_to_measure(only_slew)
    assert "tolerance" not in nothing_to_measure(quick)


@pytest.mark.parametrize(
    "argv, needle",
    [
        # bench_scenes is empty in the quick report: `--parts bench` wrote a page with a "met" target
        (
            ["--quick", "--parts", "bench"],
            "the bench part with --quick would measure nothing: the quick report has no C bench scenes",
        ),
        (["--quick", "--skip", "batch", "cosim", "long", "tolerance", "inputs"], "the quick report has no C bench"),
        (["--quick", "--parts", "bench", "batch"], "leave out --quick for it, or ask for parts that measure: batch"),
        # the inputs part has no quick form: --quick with it alone changed nothing
        (["--quick", "--parts", "inputs"], "--quick does not change the inputs part"),
        (["--quick", "--skip", "batch", "cosim", "long", "tolerance"], "add a part it shortens: batch, cosim, long"),
    ],
)
def test_a_part_that_would_measure_nothing_is_refused(argv, needle, capsys, tmp_path):
    out = tmp_path / "report"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rbfmu report: ") and needle in err and err.count("\n") == 1
    assert not out.exists()


def test_the_page_states_only_what_ran(tmp_path):
    # a run of the bench part alone with --jobs 2: the page said the batch and error-control parts
    # measured 2 scenes at once, and the whole report's time target "met"
    path = tmp_path / "report.md"
    bench = {"free_asymmetric": {"rk4": (10.0, 11.0)}}
    write_markdown(path, Config(), [], bench, None, [], {"total": 3.0, "jobs": 2, "build": 1.0, "C bench": 2.0})
    text = path.read_text()
    assert "at once" not in text
    rows = {r.split(" | ")[0].lstrip("| "): r.split(" | ")[1] for r in text.splitlines() if r.count(" | ") >= 2}
    assert rows["internal step ≤ 1.2× the raw generated step in a C loop"] == "met"
    assert rows["whole report < 10 min on 2 cores"] == "not measured"
    assert "parts not run: batch, cosim, long, tolerance, inputs" in text
    assert sum(v == "not measured" for v in rows.values()) == 3  # batch, co-simulation, whole report
    assert "## What is measured" not in text  # batch, error control, co-simulation, long horizon: none ran
    # quick: labelled as such, the total time not a measurement of the target
    write_markdown(path, Config.quick(DEFAULT_SCENES), [], {}, None, [], {"total": 3.0, "jobs": 2})
    text = path.read_text()
    assert text.startswith("# Quick work-precision report (smoke test)") and "at once" not in text
    assert "| whole report < 10 min on 2 cores | not measured | this run is not the whole report (a quick" in text
    assert _whole(Config(), PARTS) == "" and "quick" in _whole(Config.quick(DEFAULT_SCENES), PARTS)
    assert _whole(Config(scenes=("heavy_top",)), PARTS) == "scenes chosen with --scenes"
    # the jobs sentence names the parts that measured scenes at once, and only when more than one
    res = [SceneResult(n, 1.0, 0.1, 10, None, [], []) for n in ("a", "b", "c")]
    assert _jobs_txt({"jobs": 2}, res, None).startswith("; the batch part measured 2 scenes at once")
    assert _jobs_txt({"jobs": 4}, res, None).startswith("; the batch part measured 3 scenes at once")
    assert _jobs_txt({"jobs": 2}, res[:1], None) == "" == _jobs_txt({"jobs": 1}, res, None)


def test_inputs_part_builds_into_the_build_dir(fmus, tmp_path, monkeypatch, capsys):
    # --build-dir was ignored by the inputs part: its FMUs went to a temporary folder, rebuilt every run
    build = tmp_path / "build"
    build.mkdir()
    forced = [sc.name for sc in forced_inputs.forced_scenes(map(load_scene, list_scenes()))]
    for name in forced:  # built from the same sources: reused, not rebuilt
        shutil.copy(fmus[name], build / fmus[name].name)
    stamps = {p.name: p.stat().st_mtime_ns for p in build.iterdir()}
    seen: list[Path] = []

    def fake_inputs(fmu3, fmu2, progress=None):
        seen.extend([fmu3, fmu2])
        res = forced_inputs.ForcedInputsResult((0.1, 0.05), 1.0, forced_inputs.SmoothTorque())
        for mode in forced_inputs.MODES:
            res.e_w[mode], res.e_R[mode] = [1e-3, 5e-4], [1e-3, 5e-4]
            res.wall[mode], res.internal_steps[mode] = [1.0, 2.0], [1.0, 1.0]
        return res

    def fake_scenes(paths, scenes, progress=None):
        seen.extend(paths.values())
        return []

    monkeypatch.setattr(forced_inputs, "measure_forced_inputs", fake_inputs)
    monkeypatch.setattr(forced_inputs, "measure_forced_scenes", fake_scenes)
    out = tmp_path / "report"
    assert main(["--parts", "inputs", "--build-dir", str(build), "--out", str(out)]) == 0, capsys.readouterr().err
    assert seen and all(p.parent == build for p in seen)
    assert forced_inputs.SCENE in forced and (build / f"{forced_inputs.SCENE}_fmi2.fmu").is_file()
    assert all((build / n).stat().st_mtime_ns == t for n, t in stamps.items())
    assert "## Inputs inside a communication step" in (out / "report.md").read_text()


def test_an_out_that_is_a_file_or_empty_is_refused_naming_it(tmp_path, capsys):
    # it was "[Errno 17] File exists", naming no option
    a_file = tmp_path / "f"
    a_file.write_text("")
    assert main(["--quick", "--out", str(a_file)]) == 2
    assert main(["--quick", "--out", ""]) == 2
    err = capsys.readouterr().err
    assert f"--out {str(a_file)!r}: is a file" in err and "--out '': an empty path" in err
