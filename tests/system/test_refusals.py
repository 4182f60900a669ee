"""Refusals: `system build` names the bad connection or component and writes nothing; `system run` one line."""

from __future__ import annotations

import zipfile
from pathlib import Path

import pytest

from fmu.cli import main
from fmu.system.build import build_system
from fmu.system.checks import check_controller_outputs, check_feedthrough_loops, expand
from fmu.system.interface import Interface, Port
from fmu.system.system_file import read_system
from modelsrc.errors import ModelInputError

SLEW_LINKS = """
    "plant.q -> pd.q",
    "plant.w_body -> pd.w_body",
    "plant.Omega_x -> pd.Omega_x",
    "plant.Omega_y -> pd.Omega_y",
    "plant.Omega_z -> pd.Omega_z",
"""


def _system(tmp_path: Path, connections: str, step: float = 0.1, pd_params: str = "") -> Path:
    text = f"""name = "probe"
step = {step}
stop_time = 0.9
connections = [{connections}]
[components.plant]
scene = "reaction_wheel_slew"
[components.pd]
controller = "attitude_pd"
[components.pd.parameters]
{pd_params}
"""
    path = tmp_path / "probe.toml"
    path.write_text(text)
    return path


def _refused(tmp_path: Path, build_dir: Path, path: Path, *words: str) -> str:
    out = tmp_path / "out"
    with pytest.raises(ModelInputError) as exc:
        build_system(path, out, build_dir)
    msg = str(exc.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg
    assert not out.exists() or not list(out.iterdir())  # no archive, no part file
    return msg


# ---- refusals before anything is built ----


def test_unknown_component_in_a_connection(tmp_path):
    path = _system(tmp_path, '"plant.q -> ctrl.q"')
    with pytest.raises(ModelInputError, match=r"connection plant\.q -> ctrl\.q: unknown component 'ctrl'"):
        read_system(path)


def test_unknown_scene_of_a_component(tmp_path, system_build_dir):
    path = tmp_path / "s.toml"
    path.write_text('name = "s"\nstep = 0.1\n[components.plant]\nscene = "no_such_scene"\n')
    _refused(tmp_path, system_build_dir, path, "component plant", "no_such_scene")


def test_connection_not_written_as_an_arrow(tmp_path):
    path = _system(tmp_path, '"plant.q => pd.q"')
    with pytest.raises(ModelInputError, match=r"connections\[0\]: 'plant\.q => pd\.q' is not a connection"):
        read_system(path)


# ---- refusals against the components' modelDescription (FMUs from the session's cache) ----


def test_unknown_variable(tmp_path, system_build_dir):
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, '"plant.q -> pd.attitude"'),
        "connection plant.q -> pd.attitude",
        "component pd has no variable 'attitude'",
    )


def test_output_connected_to_an_output(tmp_path, system_build_dir):
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, '"plant.w_body[1] -> plant.Omega_x"'),
        "connection plant.w_body[1] -> plant.Omega_x",
        "plant.Omega_x is an output",
        "must end at an input",
    )


def test_input_connected_to_an_input(tmp_path, system_build_dir):
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, '"pd.Omega_x -> plant.u_x"'),
        "connection pd.Omega_x -> plant.u_x",
        "pd.Omega_x is an input",
        "must start at an output",
    )


def test_two_sources_for_one_input(tmp_path, system_build_dir):
    msg = _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, SLEW_LINKS + '"plant.w_body[2] -> pd.Omega_x",'),
        "input pd.Omega_x has two sources",
    )
    assert "plant.Omega_x -> pd.Omega_x" in msg and "plant.w_body[2] -> pd.Omega_x" in msg


def test_unit_mismatch(tmp_path, system_build_dir):
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, '"plant.Omega_x -> plant.u_x"'),
        "connection plant.Omega_x -> plant.u_x: unit mismatch, rad/s into N.m",
    )


def test_step_the_sample_period_is_not_a_multiple_of(tmp_path, system_build_dir):
    # Ts = 0.1 s, H = 0.03 s: 0.1/0.03 = 3.33 communication steps per sample
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, SLEW_LINKS, step=0.03),
        "component pd: its sample period Ts = 0.1 s",
        "communication step H = 0.03 s",
    )


def test_sample_period_a_whole_multiple_is_accepted(tmp_path, system_build_dir):
    # Ts = 0.1 s = 4 · 0.025 s: the controller samples every 4th communication point
    ssp = build_system(_system(tmp_path, SLEW_LINKS, step=0.025), tmp_path / "out", system_build_dir)
    assert ssp.is_file()


def test_a_parameter_that_is_no_parameter(tmp_path, system_build_dir):
    _refused(
        tmp_path,
        system_build_dir,
        _system(tmp_path, SLEW_LINKS, pd_params="u_x = 1.0"),
        "component pd: 'u_x' is not a Real parameter or input",
        "k_p",
    )


# ---- the structural checks on interfaces made here (no FMU in the project has these shapes) ----


def _iface(inputs: list[str], outputs: dict[str, list[str]], unit: str = "1") -> Interface:
    ports = {n: Port(n, "input", unit, "Real", k) for k, n in enumerate(inputs)}
    ports |= {n: Port(n, "output", unit, "Real", 100 + k) for k, n in enumerate(outputs)}
    return Interface(ports, "2.0", {o: frozenset(d) for o, d in outputs.items()})


def _probe_system(tmp_path: Path, connections: str, kinds: dict[str, str]) -> object:
    comps = "".join(f'[components.{n}]\n{k} = "x"\n' for n, k in kinds.items())
    path = tmp_path / "loop.toml"
    path.write_text(f'name = "loop"\nstep = 0.1\nconnections = [{connections}]\n{comps}')
    return read_system(path)


def test_loop_of_direct_feedthrough(tmp_path):
    # a.y depends on a.u at once, b.y on b.u: a.y -> b.u, b.y -> a.u is an algebraic loop
    system = _probe_system(tmp_path, '"a.y -> b.u", "b.y -> a.u"', {"a": "controller", "b": "controller"})
    ifaces = {"a": _iface(["u"], {"y": ["u"]}), "b": _iface(["u"], {"y": ["u"]})}
    links = expand(system, ifaces)
    with pytest.raises(ModelInputError, match=r"a loop of direct feedthrough.*a\.y -> b\.u; b\.y -> a\.u"):
        check_feedthrough_loops(links, ifaces)
    # the same wiring where b's output depends on its state only (a plant) is no loop
    ifaces["b"] = _iface(["u"], {"y": []})
    check_feedthrough_loops(links, ifaces)


def test_controller_with_more_outputs_than_its_plant_has_inputs(tmp_path):
    system = _probe_system(tmp_path, '"c.u1 -> p.v1", "c.u2 -> p.v2"', {"p": "scene", "c": "controller"})
    ifaces = {"p": _iface(["v1", "v2"], {"x": []}), "c": _iface(["x"], {"u1": ["x"], "u2": ["x"], "u3": ["x"]})}
    with pytest.raises(ModelInputError, match=r"component c: 3 outputs \(u1, u2, u3\) but its plant p has 2 input"):
        check_controller_outputs(system, expand(system, ifaces), ifaces)
    ifaces["p"] = _iface(["v1", "v2", "v3"], {"x": []})
    check_controller_outputs(system, expand(system, ifaces), ifaces)


# ---- system run on a missing or corrupt archive: one line, exit status 2 ----


@pytest.mark.parametrize(
    ("content", "words"),
    [
        (None, "no such archive"),
        (b"not a zip", "not an SSP archive (not a zip file"),
        ("zip-without-ssd", "not an SSP archive (no SystemStructure.ssd inside)"),
        ("zip-bad-xml", "SystemStructure.ssd is not valid XML"),
    ],
)
def test_run_refuses_a_missing_or_corrupt_archive(tmp_path, capsys, content, words):
    path = tmp_path / "s.ssp"
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is not None:
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("SystemStructure.ssd" if content == "zip-bad-xml" else "other.txt", "<unclosed")
    assert main(["system", "run", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not (tmp_path / "o").exists()


def test_stop_time_not_a_whole_number_of_steps(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('name = "s"\nstep = 0.1\nstop_time = 0.95\n[components.plant]\nscene = "reaction_wheel_slew"\n')
    with pytest.raises(ModelInputError, match=r"stop_time = 0\.95 s must be a whole number of communication steps"):
        read_system(path)
