"""Basilisk 2.12 against the FMU on reaction_wheel_slew's three-wheel gyrostat: CPU time at equal final error.

Basilisk (AVS Lab's spacecraft simulator, PyPI `bsk`, a 73 MB wheel and a ~800 MB venv)
stays out of the project's dependencies: run this script from a venv of its own, with the
project's venv (`make setup`) beside it for the FMU's side:

    python3 -m venv /work/bsk-venv
    /work/bsk-venv/bin/pip install 'bsk==2.12.*' scipy
    /work/bsk-venv/bin/python tools/basilisk_compare.py --project-python .venv/bin/python

The cases (CASES): reaction_wheel_slew's body and wheels (I = diag(10, 12, 8) kg m² the whole
body with the wheels' axial inertia as if locked, three wheels J = 0.02 kg m² along the body
axes, its start attitude) for T = 40 s, tumbling with the wheels spinning relative to the
body and constant motor torques on the wheels: "moderate", ω0 = (0.3, −0.5, 0.4) rad/s,
Ω0 = (300, −200, 250) rad/s, u = (0.1, −0.2, 0.05) N m (rates of a slew); "fast", ω0 = (1.0,
−1.5, 1.2) rad/s, Ω0 = (600, −400, 500) rad/s, u = (0.2, −0.3, 0.1) N m (a tumble, wheels near
their top speed). Both sides use the same conventions (docs/theory.md
§8.1; Basilisk's hub inertia is the whole body's, its wheel speed relative, its motor torque
on the wheel: measured, its RK4 at 1 ms meets the reference to 3e-12). Both exchange data at
the scene's communication step of 0.1 s: the FMU takes 400 doSteps from a C loop
(fmu/c/bench_step.c, mode cosim: a C master), Basilisk runs with a task step of 0.1 s or
less. The reference is scipy's DOP853 at rtol = atol = 1e-14 on the same equations, written
here in numpy; its own error is estimated by its distance to the FMU's tightest run.

Error of a run: e = max(‖ω − ω_ref‖∞/‖ω_ref‖∞, the angle between the attitudes (rad),
‖Ω − Ω_ref‖∞/‖Ω_ref‖∞) at T. Cost: CPU time of the integration alone (FMU: the doSteps, best
of 20 runs inside the harness; Basilisk: ExecuteSimulation, best of 3, process CPU time, since
Basilisk integrates in a worker thread). For each level 1e-6, 1e-9, 1e-11 the cheapest
setting of each side reaching it (FMU: rk4 and rk8 at fixed steps h_max, or under error
control at a tolerance; Basilisk: its RK4 at fixed task steps, RKF45 and RKF78 at a
tolerance) is timed again in ROUNDS rounds that alternate the two sides (the FMU's 0.3 ms
runs best of 50), and the median ratio of their CPU times with its spread is printed, and
with --json written to a file.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "modelsrc" / "scenes" / "reaction_wheel_slew.toml"
# name -> (ω0 (rad/s, body), Ω0 (rad/s, the wheels relative to the body), u (N m, on the wheels))
CASES = {
    "moderate": ((0.3, -0.5, 0.4), (300.0, -200.0, 250.0), (0.1, -0.2, 0.05)),
    "fast": ((1.0, -1.5, 1.2), (600.0, -400.0, 500.0), (0.2, -0.3, 0.1)),
}
T = 40.0  # s
H = 0.1  # s, the scene's communication step
LEVELS = (1e-6, 1e-9, 1e-11)
BUDGET = 5.0  # s of CPU: a ladder stops after a run this long
ROUNDS = 5  # alternating rounds that time the cheapest settings again
FMU_LADDER = [("rk4", 0.0, H / k) for k in (1, 2, 4, 8, 16, 32, 64, 128, 256)]
FMU_LADDER += [("rk8", 0.0, H / k) for k in (1, 2, 4, 8, 16)]
FMU_LADDER += [("rk8", 10.0**-e, 0.0) for e in range(5, 15)] + [("rk4", 10.0**-e, 0.0) for e in range(5, 13)]
BSK_LADDER = [("RK4", H / k, None) for k in (1, 2, 5, 10, 20, 50, 100, 200, 500)]
BSK_LADDER += [("RKF45", H, 10.0**-e) for e in range(5, 14)] + [("RKF78", H, 10.0**-e) for e in range(5, 15)]


def scene_data() -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """(principal moments I (kg m², the whole body), the wheel axes as rows, J (kg m²), q0)
    of reaction_wheel_slew, read from its scene file."""
    sc = tomllib.loads(SCENE.read_text())
    axes = np.array([r["axis"] for r in sc["rotors"].values()], dtype=float)
    Js = {float(r["J"]) for r in sc["rotors"].values()}
    if not np.allclose(axes, np.eye(3)) or len(Js) != 1:
        raise SystemExit("this comparison models three equal wheels along the body axes")
    return np.array(sc["body"]["principal_moments"], dtype=float), axes, Js.pop(), np.array(sc["initial"]["q"])


def reference(case: str) -> np.ndarray:
    """The state (q, ω, Ω) at T: scipy's DOP853 at rtol = atol = 1e-14 on the gyrostat's
    equations (docs/theory.md §8.1, axes along the body's: (I − J) ω̇ = −ω × (I ω + J Ω) − u,
    J Ω̇ = u − J ω̇ per axis, q̇ = ½ q ⊗ (0, ω))."""
    from scipy.integrate import solve_ivp

    I, _, J, q0 = scene_data()
    W0, OMEGA0, U = CASES[case]
    u = np.array(U)

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        q, w, Om = y[:4], y[4:7], y[7:]
        qd = 0.5 * np.array([-q[1] * w[0] - q[2] * w[1] - q[3] * w[2], q[0] * w[0] + q[2] * w[2] - q[3] * w[1],
                             q[0] * w[1] + q[3] * w[0] - q[1] * w[2],
                             q[0] * w[2] + q[1] * w[1] - q[2] * w[0]])  # fmt: skip
        wd = (-np.cross(w, I * w + J * Om) - u) / (I - J)
        return np.concatenate([qd, wd, u / J - wd])

    y0 = np.concatenate([q0, W0, OMEGA0])
    y = solve_ivp(rhs, (0.0, T), y0, method="DOP853", rtol=1e-14, atol=1e-14).y[:, -1]
    y[:4] /= np.linalg.norm(y[:4])
    return y


def error(y: np.ndarray, ref: np.ndarray) -> float:
    """e of the module docstring for the state y = (q, ω, Ω) at T."""
    q = y[:4] if np.dot(y[:4], ref[:4]) >= 0 else -y[:4]
    angle = 4 * math.asin(min(1.0, float(np.linalg.norm(q - ref[:4])) / 2))  # |q - q_ref| = 2 sin(angle/4)
    rate = float(np.max(np.abs(y[4:7] - ref[4:7])) / np.max(np.abs(ref[4:7])))
    wheels = float(np.max(np.abs(y[7:] - ref[7:])) / np.max(np.abs(ref[7:])))
    return max(rate, angle, wheels)


def basilisk_run(case: str, integrator: str, dt: float, tol: float | None) -> tuple[float, np.ndarray]:
    """(CPU s of ExecuteSimulation, the state at T) of Basilisk on `case` with `integrator`
    (RK4, RKF45, RKF78) at the task step dt (s) and relative and absolute tolerance tol."""
    from Basilisk.architecture import messaging
    from Basilisk.simulation import reactionWheelStateEffector, spacecraft, svIntegrators
    from Basilisk.utilities import SimulationBaseClass, macros, simIncludeRW

    I, axes, J, q0 = scene_data()
    W0, OMEGA0, U = CASES[case]
    sim = SimulationBaseClass.SimBaseClass()
    sim.CreateNewProcess("dynamics").addTask(sim.CreateNewTask("task", macros.sec2nano(dt)))
    sc = spacecraft.Spacecraft()
    sc.ModelTag = "gyrostat"
    sc.hub.mHub = 100.0  # kg: the centre of mass stays at rest, the mass does not enter the rotation
    sc.hub.IHubPntBc_B = np.diag(I).tolist()  # the whole body's, wheels' axial inertia included (as the scene's)
    sc.hub.sigma_BNInit = (q0[1:] / (1 + q0[0])).reshape(3, 1).tolist()  # MRP of q0
    sc.hub.omega_BN_BInit = np.reshape(W0, (3, 1)).tolist()
    factory = simIncludeRW.rwFactory()
    for axis, Om in zip(axes, OMEGA0, strict=True):
        rw = factory.create("custom", axis.tolist(), Omega=Om / macros.RPM, Js=J, useRWfriction=False,
                            useMaxTorque=False, RWModel=messaging.BalancedWheels)  # fmt: skip
        rw.Jt = rw.Jg = rw.mass = 0.0  # a wheel adds only its axial inertia, as in the scene
    wheels = reactionWheelStateEffector.ReactionWheelStateEffector()
    factory.addToSpacecraft("wheels", wheels, sc)
    command = messaging.ArrayMotorTorqueMsgPayload()
    command.motorTorque = list(U)
    message = messaging.ArrayMotorTorqueMsg().write(command)
    wheels.rwMotorCmdInMsg.subscribeTo(message)
    integ = {"RK4": svIntegrators.svIntegratorRK4, "RKF45": svIntegrators.svIntegratorRKF45,
             "RKF78": svIntegrators.svIntegratorRKF78}[integrator](sc)  # fmt: skip
    if tol is not None:
        integ.relTol = tol
        integ.absTol = tol
    sc.setIntegrator(integ)
    sim.AddModelToTask("task", wheels)
    sim.AddModelToTask("task", sc)
    sim.InitializeSimulation()
    sim.ConfigureStopTime(macros.sec2nano(T))
    cpu = time.process_time()
    sim.ExecuteSimulation()
    cpu = time.process_time() - cpu
    state = sc.scStateOutMsg.read()
    s = np.array(state.sigma_BN)
    s2 = float(s @ s)
    q = np.concatenate([[(1 - s2) / (1 + s2)], 2 * s / (1 + s2)])
    return cpu, np.concatenate([q, state.omega_BN_B, np.array(wheels.rwSpeedOutMsg.read().wheelSpeeds[:3])])


def bsk_setting(integrator: str, dt: float, tol: float | None) -> str:
    """How the tables name a Basilisk setting."""
    return f"{integrator} dt={dt:g}" + (f" tol={tol:g}" if tol else "")


def basilisk_ladder(case: str, ref: np.ndarray) -> list[dict]:
    """Every Basilisk setting of BSK_LADDER (each integrator's rungs until one costs BUDGET)."""
    out: list[dict] = []
    stopped: set[str] = set()
    for integrator, dt, tol in BSK_LADDER:
        if integrator in stopped:
            continue
        runs = [basilisk_run(case, integrator, dt, tol) for _ in range(1 if out and out[-1]["cpu"] > 0.5 else 3)]
        cpu = min(r[0] for r in runs)
        out.append(dict(side="Basilisk", setting=bsk_setting(integrator, dt, tol), cpu=cpu,
                        error=error(runs[0][1], ref)))  # fmt: skip
        print(f"  Basilisk {out[-1]['setting']}: e = {out[-1]['error']:.2e}, {cpu * 1e3:.2f} ms", flush=True)
        if cpu > BUDGET or out[-1]["error"] < 1e-13:
            stopped.add(integrator)
    return out


def fmu_side(case: str, out_dir: str) -> None:
    """In the project's venv: build reaction_wheel_slew's FMU and the C harness
    (fmu/c/bench_step.c) into out_dir, run FMU_LADDER from it (fmu.bench.benchmark.c_cosim) and
    print the harness's path, the methods' enumeration values and the runs as JSON."""
    sys.path.insert(0, str(ROOT))
    from fmu.bench.benchmark import c_cosim, compile_harness
    from fmu.build.build_fmu import build_fmu
    from modelsrc.methods import METHODS

    _, _, _, q0 = scene_data()
    W0, OMEGA0, U = CASES[case]
    fmu = build_fmu("reaction_wheel_slew", out_dir)
    harness = Path(out_dir) / "harness"
    harness.mkdir(parents=True, exist_ok=True)
    exe = compile_harness(fmu, harness)
    runs = []
    for method, tol, h_max in FMU_LADDER:
        x0 = [*q0, *W0, *OMEGA0]
        cpu, steps, x = c_cosim(exe, round(T / H), METHODS[method].value, H, tol, h_max, x0, U, repeats=20)
        runs.append(dict(method=method, tolerance=tol, h_max=h_max, cpu=cpu, steps=steps, x=x.tolist()))
    values = {m: METHODS[m].value for m in ("rk4", "rk8")}
    print(json.dumps(dict(exe=str(exe), values=values, runs=runs)))


def fmu_cosim(exe: str, value: int, case: str, tol: float, h_max: float, repeats: int) -> float:
    """CPU s of the FMU's 400 doSteps (best of `repeats`), the harness run directly (its mode
    cosim: bench cosim N METHOD_VALUE H TOLERANCE H_MAX REPEATS X U)."""
    _, _, _, q0 = scene_data()
    W0, OMEGA0, U = CASES[case]
    args = [exe, "cosim", str(round(T / H)), str(value), repr(H), repr(tol), repr(h_max), str(repeats)]
    args += [repr(float(v)) for v in (*q0, *W0, *OMEGA0, *U)]
    return float(subprocess.run(args, capture_output=True, text=True, check=True).stdout.split()[0])


def cheapest(runs: list[dict], level: float) -> dict | None:
    """The run of least CPU time whose error is at most `level`, None if none reaches it."""
    ok = [r for r in runs if r["error"] <= level]
    return min(ok, key=lambda r: r["cpu"]) if ok else None


def compare(case: str, project_python: str, out_dir: str) -> dict:
    """Both ladders on `case`; the cheapest setting of each side per level, timed again in
    ROUNDS alternating rounds (FMU best of 50, Basilisk best of 3); the table printed. Returns
    the runs and the table."""
    print(f"case {case}: ω0 = {CASES[case][0]} rad/s, Ω0 = {CASES[case][1]} rad/s, u = {CASES[case][2]} N m")
    ref = reference(case)
    print("the FMU's runs (C loop of 400 doSteps of 0.1 s, CPU best of 20) ...", flush=True)
    proc = subprocess.run([project_python, __file__, "--fmu-side", case, "--out", out_dir], capture_output=True,
                          text=True, check=True)  # fmt: skip
    fmu = json.loads(proc.stdout.strip().splitlines()[-1])
    fmu_runs = fmu["runs"]
    for r in fmu_runs:
        r.update(side="FMU", error=error(np.array(r.pop("x")), ref))
        how = f"tolerance={r['tolerance']:g}" if r["tolerance"] else f"h_max={r['h_max']:g}"
        r["setting"] = f"{r['method']} {how}"
        print(f"  FMU {r['setting']}: e = {r['error']:.2e}, {r['steps']} internal steps, {r['cpu'] * 1e3:.3f} ms")
    floor = min(r["error"] for r in fmu_runs)
    print(f"reference: scipy DOP853 rtol = atol = 1e-14; the FMU's closest run is {floor:.1e} from it")
    print("Basilisk's runs (CPU best of 3 below 0.5 s) ...", flush=True)
    bsk_runs = basilisk_ladder(case, ref)
    rows = []
    print(f"\nthe cheapest of each side per level, timed again in {ROUNDS} alternating rounds (ratio: median, spread)")
    print(f"{'level':>8}  {'FMU':<24}{'CPU ms':>8}  {'Basilisk':<26}{'CPU ms':>9}{'ratio':>7}{'min..max':>12}")
    for level in LEVELS:
        f, b = cheapest(fmu_runs, level), cheapest(bsk_runs, level)
        if f is None or b is None:
            rows.append(dict(level=level, fmu=f and f["setting"], basilisk=b and b["setting"], ratio=None))
            print(f"{level:>8.0e}  {'not reached' if f is None else f['setting']:<24}{'':8}  "
                  f"{'not reached' if b is None else b['setting']:<26}")  # fmt: skip
            continue
        fc, bc = [], []
        for _ in range(ROUNDS):
            fc.append(fmu_cosim(fmu["exe"], fmu["values"][f["method"]], case, f["tolerance"], f["h_max"], 50))
            spec = next(s for s in BSK_LADDER if b["setting"] == bsk_setting(*s))
            bc.append(min(basilisk_run(case, *spec)[0] for _ in range(3)))
        ratios = np.array(bc) / np.array(fc)
        row = dict(level=level, fmu=f["setting"], fmu_error=f["error"], fmu_cpu=float(np.median(fc)),
                   basilisk=b["setting"], basilisk_error=b["error"], basilisk_cpu=float(np.median(bc)),
                   ratio=float(np.median(ratios)), ratio_min=float(ratios.min()), ratio_max=float(ratios.max()),
                   resolved=level >= 10 * floor)  # fmt: skip
        rows.append(row)
        note = "" if row["resolved"] else "  (below 10x the reference's own error)"
        spread = f"{ratios.min():.0f}..{ratios.max():.0f}"
        print(f"{level:>8.0e}  {f['setting']:<24}{row['fmu_cpu'] * 1e3:8.3f}  {b['setting']:<26}"
              f"{row['basilisk_cpu'] * 1e3:9.2f}{row['ratio']:7.0f}{spread:>12}{note}")  # fmt: skip
    print()
    return dict(case=case, fmu=fmu_runs, basilisk=bsk_runs, table=rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=sorted(CASES), action="append", help="a case (default: every case)")
    parser.add_argument("--project-python", default=str(ROOT / ".venv" / "bin" / "python"))
    parser.add_argument("--out", default=str(ROOT / "build" / "basilisk_compare"), help="where the FMU is built")
    parser.add_argument("--json", help="write the runs and the tables to this file")
    parser.add_argument("--fmu-side", choices=sorted(CASES), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.fmu_side:
        fmu_side(args.fmu_side, args.out)
        return 0
    results = [compare(case, args.project_python, args.out) for case in args.case or list(CASES)]
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
