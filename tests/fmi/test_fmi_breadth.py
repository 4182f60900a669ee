"""FMI breadth: FMI 2.0 and 3.0, CS and ME in one archive, FMU state, directional and adjoint derivatives.

FMU state with rollback and serialisation."""

from __future__ import annotations

import ctypes
import shutil

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu

from fmu.build.build_fmu import build_fmu
from modelsrc.scene import list_scenes, load_scene
from rbcheck.closed_forms import free_symmetric

SCENES = list_scenes()


@pytest.fixture(scope="session")
def fmus2(build_dir):
    """Scene name -> FMI 2.0 FMU path."""
    return {name: build_fmu(load_scene(name), build_dir, fmi_version=2) for name in SCENES}


def fmu_path(fmus, fmus2, scene, version):
    return fmus[scene] if version == 3 else fmus2[scene]


class Opened:
    """An initialised instance of either version and interface type, through fmpy."""

    def __init__(self, path, version: int, kind: str, start: dict | None = None):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.dir = extract(str(path))
        self.version, self.kind = version, kind
        cls = {(3, "cs"): FMU3Slave, (3, "me"): FMU3Model, (2, "cs"): FMU2Slave, (2, "me"): FMU2Model}[(version, kind)]
        ident = (self.md.coSimulation if kind == "cs" else self.md.modelExchange).modelIdentifier
        self.fmu = cls(guid=self.md.guid, unzipDirectory=self.dir, modelIdentifier=ident, instanceName="t")
        self.fmu.instantiate()
        if version == 2:
            self.fmu.setupExperiment(startTime=0.0)
        if start:
            self.set(start)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        if kind == "me":
            if version == 3:
                self.fmu.updateDiscreteStates()
            else:
                self.fmu.newDiscreteStates()
            self.fmu.enterContinuousTimeMode()

    def set(self, values: dict):
        vrs, vals = [self.vr[n] for n in values], [float(v) for v in values.values()]
        (self.fmu.setFloat64 if self.version == 3 else self.fmu.setReal)(vrs, vals)

    def get(self, names):
        vrs = [self.vr[n] for n in names]
        return np.array((self.fmu.getFloat64 if self.version == 3 else self.fmu.getReal)(vrs))

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES)
def test_fmi2_validates_and_has_both_interfaces(fmus2, scene):
    path = fmus2[scene]
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.fmiVersion == "2.0" and md.coSimulation is not None and md.modelExchange is not None


def test_fmi3_has_both_interfaces_and_capabilities(fmus):
    md = read_model_description(str(fmus["heavy_top"]))
    assert md.coSimulation is not None and md.modelExchange is not None
    import xml.etree.ElementTree as ET
    import zipfile

    with zipfile.ZipFile(fmus["heavy_top"]) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    for tag in ("CoSimulation", "ModelExchange"):  # read the XML: fmpy parses FMI 2.0 spellings only
        el = root.find(tag)
        for cap in (
            "canGetAndSetFMUState",
            "canSerializeFMUState",
            "providesDirectionalDerivatives",
            "providesAdjointDerivatives",
        ):
            assert el.get(cap) == "true", (tag, cap)
    assert len(md.derivatives) == 7


@pytest.mark.parametrize("version", [3, 2])
def test_model_exchange_under_cvode_matches_co_simulation(fmus, fmus2, version):
    """ME integrated by fmpy's CVODE vs the FMU's own CS integration, same outputs."""
    path = fmu_path(fmus, fmus2, "symmetric_free", version)
    sc = load_scene("symmetric_free")
    out = ["w_body[1]", "w_body[2]", "w_body[3]", "q[1]", "q[2]", "q[3]", "q[4]"]
    cs = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=5.0, output_interval=0.01, output=out)
    me = simulate_fmu(
        str(path),
        fmi_type="ModelExchange",
        solver="CVode",
        relative_tolerance=1e-10,
        stop_time=5.0,
        output_interval=0.01,
        output=out,
    )
    w_ref, _q_ref = free_symmetric.solve(1.0, 1.6, sc.w0, sc.q0, cs["time"])
    w_cs = np.column_stack([cs[f"w_body[{k}]"] for k in (1, 2, 3)])
    w_me = np.column_stack([me[f"w_body[{k}]"] for k in (1, 2, 3)])
    e_cs, e_me = np.abs(w_cs - w_ref).max(), np.abs(w_me - w_ref).max()
    print(f"\nFMI {version}: max |ω − closed form| CS (RK4 h=1e-3) {e_cs:.2e}, ME (CVODE rtol 1e-10) {e_me:.2e}")
    # RK4 at h = 1e-3: ~1e-12; CVODE's global error is a small multiple of its rtol·|ω| ≈ 2e-10
    assert e_cs < 1e-10
    assert e_me < 1e-7
    assert np.abs(w_cs - w_me).max() < 1e-7


@pytest.mark.parametrize("version", [3, 2])
def test_model_exchange_outputs_normalise_a_drifted_quaternion(fmus, fmus2, version):
    inst = Opened(fmu_path(fmus, fmus2, "heavy_top", version), version, "me")
    try:
        x = np.array(inst.get([f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in (1, 2, 3)]))
        x_drift = x.copy()
        x_drift[:4] *= 1.1  # an importer's solver lets |q| drift
        inst.fmu.setContinuousStates((ctypes.c_double * 7)(*x_drift), 7)
        ww = inst.get(["w_world[1]", "w_world[2]", "w_world[3]"])
        E = inst.get(["E_total"])[0]
        inst.fmu.setContinuousStates((ctypes.c_double * 7)(*x), 7)
        E_unit = inst.get(["E_total"])[0]
        # R(q) is the rotation of q/|q|: |ω_world| = |ω_body|, and the potential is unchanged
        assert np.linalg.norm(ww) == pytest.approx(np.linalg.norm(x[4:]), rel=1e-14)
        assert pytest.approx(E_unit, rel=1e-14) == E
    finally:
        inst.close()


@pytest.mark.parametrize("version", [3, 2])
@pytest.mark.parametrize("kind", ["cs", "me"])
def test_directional_derivatives_match_finite_differences(fmus, fmus2, version, kind):
    path = fmu_path(fmus, fmus2, "torque_driven", version)
    start = {
        "w_body[1]": 0.3,
        "w_body[2]": -0.5,
        "w_body[3]": 0.7,
        "tau_body[1]": 0.2,
        "tau_world[2]": -0.1,
        "q[1]": 0.9,
        "q[2]": 0.3,
        "q[3]": -0.2,
        "q[4]": 0.4**0.5 * (1 - 0.81 - 0.09 - 0.04) ** 0.5 / 0.4**0.5,
    }
    inst = Opened(path, version, kind, start)
    try:
        states = [f"q[{k}]" for k in range(1, 5)] + [f"w_body[{k}]" for k in (1, 2, 3)]
        inputs = [f"tau_body[{k}]" for k in (1, 2, 3)] + [f"tau_world[{k}]" for k in (1, 2, 3)]
        ders = [f"der({s})" for s in states]
        outs = ["w_world[1]", "w_world[2]", "w_world[3]", "E_kin", "L_world[1]", "euler_zxz[2]"]
        knowns = inputs if kind == "cs" else states + inputs  # CS: states are not settable in step mode
        unknowns = outs if kind == "cs" else ders + outs
        ku, kk = [inst.vr[n] for n in unknowns], [inst.vr[n] for n in knowns]
        J = np.zeros((len(unknowns), len(knowns)))
        for j in range(len(knowns)):
            seed = np.zeros(len(knowns))
            seed[j] = 1.0
            J[:, j] = inst.fmu.getDirectionalDerivative(ku, kk, list(seed))
        # central differences through the FMU's own setters (h = 1e-6: error O(h²)·|f'''| ~ 1e-12,
        # round-off O(eps/h) ~ 1e-10)
        h = 1e-6
        x0 = inst.get(knowns)
        J_fd = np.zeros_like(J)
        for j, name in enumerate(knowns):
            vals = []
            for sgn in (1, -1):
                if kind == "me" and name in states:
                    x = inst.get(states)
                    x[states.index(name)] = x0[j] + sgn * h
                    inst.fmu.setContinuousStates((ctypes.c_double * 7)(*x), 7)
                else:
                    inst.set({name: x0[j] + sgn * h})
                vals.append(inst.get(unknowns))
            if kind == "me" and name in states:
                inst.fmu.setContinuousStates((ctypes.c_double * 7)(*x0[:7]), 7)
            else:
                inst.set({name: x0[j]})
            J_fd[:, j] = (vals[0] - vals[1]) / (2 * h)
        err = np.abs(J - J_fd).max()
        print(f"\nFMI {version} {kind}: {J.shape} Jacobian, max |AD − FD| = {err:.2e}, max |J| = {np.abs(J).max():.2e}")
        assert err < 1e-8 * max(1.0, np.abs(J).max())
        if kind == "cs":
            # no direct feedthrough: the outputs depend on the state only, so ∂y/∂u = 0 exactly
            assert np.all(J == 0.0)
        else:
            assert np.abs(J).max() > 0.1  # the state derivatives do depend on states and torques
        if version == 3:  # adjoint: vᵀ (J w) = (Jᵀ v)ᵀ w
            rng = np.random.default_rng(0)
            v, w = rng.normal(size=len(unknowns)), rng.normal(size=len(knowns))
            Jw = np.array(inst.fmu.getDirectionalDerivative(ku, kk, list(w)))
            JTv = np.array(inst.fmu.getAdjointDerivative(ku, kk, list(v), nSensitivity=len(knowns)))
            assert v @ Jw == pytest.approx(JTv @ w, rel=1e-13, abs=1e-14)
    finally:
        inst.close()


@pytest.mark.parametrize("version", [3, 2])
def test_rollback_reproduces_a_step_bit_for_bit(fmus, fmus2, version):
    path = fmu_path(fmus, fmus2, "heavy_top", version)
    names = ["q[1]", "q[2]", "q[3]", "q[4]", "w_body[1]", "w_body[2]", "w_body[3]", "E_total"]
    inst = Opened(path, version, "cs")
    other = Opened(path, version, "cs")
    try:
        f = inst.fmu
        get_state = f.getFMUState if version == 3 else f.getFMUstate
        set_state = f.setFMUState if version == 3 else f.setFMUstate
        serialize = f.serializeFMUState if version == 3 else f.serializeFMUstate
        t = 0.0
        for _ in range(7):
            f.doStep(t, 0.01)
            t += 0.01
        s = get_state()
        blob = serialize(s)
        f.doStep(t, 0.05)
        first = inst.get(names)
        for _ in range(3):  # roll back and redo: identical bits every time
            set_state(s)
            f.doStep(t, 0.05)
            assert np.array_equal(inst.get(names), first)
        # the serialised state, restored into another instance of the same FMU
        o = other.fmu
        s2 = o.deserializeFMUState(blob) if version == 3 else o.deSerializeFMUstate(blob)
        (o.setFMUState if version == 3 else o.setFMUstate)(s2)
        o.doStep(t, 0.05)
        assert np.array_equal(other.get(names), first)
    finally:
        inst.close()
        other.close()


def test_serialized_state_of_another_build_is_refused(fmus):
    a, b = Opened(fmus["heavy_top"], 3, "cs"), Opened(fmus["symmetric_free"], 3, "cs")
    try:
        blob = a.fmu.serializeFMUState(a.fmu.getFMUState())
        with pytest.raises(Exception):
            b.fmu.deserializeFMUState(blob)
    finally:
        a.close()
        b.close()


@pytest.mark.slow
def test_cli_builds_fmi2(tmp_path):
    import subprocess
    import sys

    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "fmu.cli",
            "build",
            "symmetric_free",
            "--fmi-version",
            "2",
            "--out",
            str(tmp_path),
            "--platforms",
            "host",
        ],  # fmt: skip  (the cross builds: tests/platforms/test_platforms.py)
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert read_model_description(str(tmp_path / "symmetric_free_fmi2.fmu")).fmiVersion == "2.0"
