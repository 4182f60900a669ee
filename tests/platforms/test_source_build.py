"""A plain `cc -shared -fPIC -O2 sources/*.c` build, with no CMake and no flags of ours, is the shipped binary.

FMI tools that build from buildDescription.xml, and people who build by hand, pass
their own flags. The sources carry what matters themselves (fmu/c/rbfmu_build.h, first
in every unit, the generated one included): only the fmi3* functions are exported, and
no multiply-add is contracted into an FMA. So the plain build exports exactly the 75
functions of fmi3Functions.h and gives the shipped binary's results bit for bit, and two
such FMUs of different scenes loaded RTLD_GLOBAL into one process each run their own
core (with the internal rb_* / model_* symbols exported, the second instance would bind
to the first FMU's core and refuse its own instantiation token).
"""

from __future__ import annotations

import ctypes as C
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import load_scene

from ..harness.fmi3_ctypes import Fmi3Library, extract_fmu
from ..harness.scenes import write_scene

# Two small scenes with different models (one method each: the smallest generated C).
SCENES = {
    "src_free": """
name = "src_free"
description = "Principal body spinning near its major axis (source-build tests)."
outputs = ["q", "w_body"]
[body]
principal_moments = [1.0, 2.0, 3.0]
[initial]
w_body = [0.3, 0.2, 2.0]
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
methods = ["rk4"]
""",
    "src_friction": """
name = "src_friction"
description = "Asymmetric body slowed by viscous friction (source-build tests)."
outputs = ["q", "w_body"]
[features]
friction = true
[body]
principal_moments = [2.0, 3.0, 5.0]
[friction]
c = 0.4
[initial]
w_body = [1.0, -0.5, 0.7]
[experiment]
stop_time = 1.0
step = 0.01
h_max = 0.001
methods = ["rk4"]
""",
}
STEPS, STEP_SIZE = 200, 0.01
CC = shutil.which("cc") or shutil.which("gcc")


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> dict[str, tuple[Path, Path]]:
    """Scene name -> (extracted FMU, its sources/ built by plain `cc -shared -fPIC -O2`)."""
    if CC is None:
        pytest.skip("no C compiler (cc or gcc) on PATH")
    out = tmp_path_factory.mktemp("source_build")
    result = {}
    for name, text in SCENES.items():
        fmu = build_fmu(load_scene(write_scene(out, text, name)), out / name)
        d = extract_fmu(fmu, out / name / "unzipped")
        lib = out / name / f"plain_{name}.so"
        sources = sorted(str(p) for p in (d / "sources").glob("*.c"))
        subprocess.run([CC, "-shared", "-fPIC", "-O2", "-o", str(lib), *sources, "-lm"], check=True)
        result[name] = (d, lib)
    return result


def _run(lib: Fmi3Library) -> list[float]:
    """q and ω_body after every one of STEPS communication steps, from the default start."""
    inst = lib.instantiate()
    assert inst.handle, inst.log
    vrs = [vr for name, vr in lib.info.vr.items() if name.startswith(("q[", "w_body["))]
    assert inst.enter_initialization_mode() == 0 and inst.exit_initialization_mode() == 0
    values: list[float] = []
    for k in range(STEPS):
        assert inst.do_step(k * STEP_SIZE, STEP_SIZE)[0] == 0, inst.log
        status, v = inst.get_float64(vrs)
        assert status == 0
        values += v
    inst.terminate()
    inst.free()
    return values


def test_a_plain_cc_build_exports_only_the_fmi3_functions(built):
    lief = pytest.importorskip("lief")
    lief.logging.disable()
    d, lib = built["src_free"]
    header = (d / "sources/fmi3Functions.h").read_text()
    declared = set(re.findall(r"^FMI3_Export\s+\w+TYPE\s+(fmi3\w+);", header, re.M))
    exported = {f.name for f in lief.parse(str(lib)).exported_functions}
    assert len(declared) == 75 and exported == declared  # no rb_*, no model_* (before: 419 exports)


def test_a_plain_cc_build_gives_the_shipped_binarys_results_bit_for_bit(built):
    d, plain = built["src_friction"]
    shipped = _run(Fmi3Library(d))
    assert _run(Fmi3Library(d, so_path=plain)) == shipped  # every bit, no tolerance


def test_two_plain_builds_loaded_rtld_global_each_run_their_own_model(built, tmp_path):
    expected = {name: _run(Fmi3Library(d)) for name, (d, _) in built.items()}  # shipped, RTLD_LOCAL
    # fresh copies: a library another test already loaded would keep the bindings of that load
    copies = {name: tmp_path / f"global_{plain.name}" for name, (_, plain) in built.items()}
    for name, (_, plain) in built.items():
        shutil.copy(plain, copies[name])
    libs = {name: Fmi3Library(d, so_path=copies[name], mode=C.RTLD_GLOBAL) for name, (d, _) in built.items()}
    for name, lib in libs.items():  # the second one loaded too: its own token, its own equations
        assert _run(lib) == expected[name], name
    assert expected["src_free"] != expected["src_friction"]
