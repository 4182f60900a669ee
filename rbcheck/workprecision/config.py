"""Configuration of a work-precision report run: ladders, time caps, problem sizes, error levels and targets."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from .measurable import measurable_scenes

# Relative to the current directory: `make demo` writes out/report, `make report-docs`
# regenerates the committed docs/report/.
DEFAULT_OUT = Path("out") / "report"
DEFAULT_SCENES = (
    "symmetric_free",
    "free_asymmetric",
    "heavy_top",
    "sleeping_top",
    "torque_driven",
    "thrown_racket",
    "spacecraft_thruster",
    "top_on_shaker",
    "gravity_gradient_boom",
    "dual_spin",
    "reaction_wheel_slew",  # as rbcheck.workprecision.report_scenes runs it: open loop
    "quadrotor",  # ... and with constant rotor speeds
    "skewed_bar",  # the held rate: against its closed form, scipy, no Exudyn line (rbcheck.exudyn.coverage)
    "two_frame_arm",
    "eccentric_orbit",  # a central field: scipy only
    "momentum_bias",  # an orbit with a wheel: scipy only
)
LEVELS = tuple(10.0**-k for k in range(4, 12))  # error levels of the table, 1e-4 ... 1e-11
ERR_FLOOR = 1e-17  # errors are clamped here before taking logs (exact agreement happens)
EXUDYN_EXPLICIT = ("RK44", "RK67", "DOPRI5")
EXUDYN_IMPLICIT = ("TrapezoidalIndex2", "GeneralizedAlpha")

# Targets; the report states and evaluates them in its "Targets" table (docs/report/report.md).
TARGET_STEP_RATIO = 1.2  # internal step through fmi3DoStep <= 1.2 x the raw generated step
TARGET_BATCH_SPEEDUP = 10.0  # batch: best FMU line vs best Exudyn and best scipy line, every resolved level
TARGET_COSIM_SPEEDUP = 50.0  # co-simulation: FMU loop vs Exudyn chunk by chunk, at least as accurate
TARGET_TOTAL_S = 600.0  # the whole report on 2 cores, s
# The short report of `make demo` (`rbfmu report --short`): this many rungs of every
# ladder, spread over its range; the batch part only.
SHORT_RUNGS = 3
SHORT_PARTS = ("batch",)
# The report's parts (`rbfmu report --parts`), in the order they are listed
PARTS = ("batch", "cosim", "long", "bench", "tolerance", "inputs")
# ... and those --quick leaves as they are (forced_inputs: its runs take seconds already)
QUICK_SAME = ("inputs",)
# ... and over these stop times (s) where a scene's own costs seconds per baseline run
# (the tops spin at ~150 rad/s: Exudyn's implicit solvers on the jointed top cannot step
# coarser than h·ω = 2^-7, 1.5e5 steps for sleeping_top's 8 s, ~3 s a run)
# (dual_spin needs none: without Exudyn's implicit solvers, the only ones its jointed
# gyrostat takes, its 60 s cost 4.4 s of CPU for `rbfmu report --short --scenes dual_spin`,
# start-up included, against 3.3 s for symmetric_free; measured on a loaded 2-core machine)
# (reaction_wheel_slew, run open loop on 400 table rows, over its first 10 s: the wheels spin
# up to 110 rad/s and back; its 40 s cost 1.9 s of CPU in the short report, 10 s cost ~1 s;
# quadrotor needs none: ~1 s)
SHORT_STOP_TIME = {"sleeping_top": 1.0, "top_on_shaker": 0.5, "reaction_wheel_slew": 10.0}


def pow2(a: int, b: int) -> tuple[float, ...]:
    """2^-a, 2^-(a+1), ..., 2^-b (a may be negative: coarser than 1)."""
    return tuple(2.0**-k for k in range(a, b + 1))


def thin_ladder(ladder: Sequence[float], rungs: int) -> tuple[float, ...]:
    """`rungs` rungs of `ladder` spread evenly over it, its first and last included (all of
    it when it has no more)."""
    if len(ladder) <= rungs:
        return tuple(ladder)
    picks = sorted({round(k * (len(ladder) - 1) / (rungs - 1)) for k in range(rungs)})
    return tuple(ladder[k] for k in picks)


@dataclass
class Config:
    """Ladders, time caps and problem sizes of one report run.

    Step ladders are in θ = h·Ω (dimensionless rotation per internal step, Ω the scene's
    largest |ω|, rad/s), so one ladder serves a top at 150 rad/s and a body at 1 rad/s.
    A ladder stops early when its next rung is predicted to take more than the family's
    cap (s), when the error has reached `floor`, or when it stopped decreasing (round-off).
    """

    scenes: tuple[str, ...] = DEFAULT_SCENES
    comm_fraction: int = 10  # batch mode: communication step T/10
    fmu_theta: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "rk4": pow2(1, 12),
            "rk8": pow2(-1, 8),
            "implicit_midpoint": pow2(2, 16),
            "gauss4": pow2(1, 10),
            "gauss6": pow2(-1, 8),
            "splitting": pow2(2, 16),
            # exact for a torque-free body at any step, order 2 (kick - flow - kick) with torques
            "exact_free": pow2(-1, 16),
        }
    )
    # ladder of a method the FMU has but fmu_theta does not name (None: skip such methods)
    fmu_theta_default: tuple[float, ...] | None = pow2(1, 14)
    exudyn_theta: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "RK44": pow2(1, 12),
            "RK67": pow2(-1, 10),
            "TrapezoidalIndex2": pow2(3, 16),
            "GeneralizedAlpha": pow2(3, 16),
        }
    )
    # Exudyn's generalized-α on the jointed top diverges for h·ω ≥ 0.015 (measured on
    # heavy_top, 1.13.6: 9e5 steps and ω = 1.6e5 rad/s at h = 1e-4 s), so the jointed
    # model's implicit ladders start at θ = 2^-7.
    joint_theta_start: float = 2.0**-7
    dopri_tol: tuple[float, ...] = tuple(10.0**-k for k in range(1, 14))
    scipy_rtol: dict[str, tuple[float, ...]] = field(
        default_factory=lambda: {
            "DOP853": tuple(10.0**-k for k in range(1, 14)),
            "Radau": tuple(10.0**-k for k in range(1, 12)),
            "LSODA": tuple(10.0**-k for k in range(1, 14)),
        }
    )
    atol_factor: float = 1e-3  # scipy: atol = 1e-3 · rtol, on every state (q is O(1), ω in rad/s)
    cap_fmu: float = 1.0
    cap_exudyn: float = 2.0
    cap_scipy: float = 2.0
    floor: float = 3e-13
    max_repeats: int = 5
    # co-simulation
    cosim_scene: str = "torque_driven"
    cosim_dt: float = 1e-3
    cosim_T: float = 4.0
    # long horizon
    long_scene: str = "free_asymmetric"
    long_steps: int = 10_000_000
    long_budget: float = 10.0  # s: a method whose projected full run exceeds this stops at its first tenth
    long_chunks: int = 100
    # C step cost
    # (reaction_wheel_slew: the three-wheel gyrostat's step cost, for its comparison with a
    # spacecraft simulator's step: simulator_compare)
    bench_scenes: tuple[str, ...] = ("free_asymmetric", "heavy_top", "torque_driven", "reaction_wheel_slew")
    bench_n_explicit: int = 200_000
    bench_n_implicit: int = 5_000
    # error control (tolerance part, rbcheck.workprecision.tolerance): tolerances in 1/s
    # (relative error per second, modelsrc.methods.DEFAULT_TOLERANCE), scenes (None: every
    # shipped scene it can measure, tolerance.measurable_scenes), shorter stop times (s)
    # where a scene's own would cost minutes, the time cap per run (s), and the fast-spin
    # cases (torque-free scene, rates rad/s, directions of ω0 in the body frame,
    # communication step and stop time in s)
    tolerances: tuple[float, ...] = tuple(10.0**-k for k in range(3, 13))
    tol_scenes: tuple[str, ...] | None = None
    tol_stop_time: dict[str, float] = field(default_factory=dict)
    tol_cap: float = 0.3
    spin_scene: str = "free_asymmetric"
    spin_rates: tuple[float, ...] = (1e4, 1e5)
    spin_bodies: dict[str, tuple[float, float, float]] = field(
        default_factory=lambda: {"near the major axis": (1e-3, 0.0, 1.0), "tennis racket": (0.01, 1.0, 0.01)}
    )
    spin_step: float = 1e-2
    spin_T: float = 1.0
    # > 0: a short report (Config.short) of this many rungs per ladder; 0: the full one
    short_rungs: int = 0
    # the quick report (Config.quick): a smoke test, labelled as such
    quick_report: bool = False
    # batch part: stop times (s) shorter than a scene's own (the short report's; the full
    # report runs every scene over its own stop time)
    batch_stop_time: dict[str, float] = field(default_factory=dict)

    @staticmethod
    def short(scenes: Sequence[str] = DEFAULT_SCENES, rungs: int = SHORT_RUNGS) -> Config:
        """The short report `make demo` writes: every ladder of the full configuration cut to
        `rungs` rungs spread evenly over it (coarsest and finest kept; scipy's and Exudyn
        DOPRI5's tolerance ladders over their coarser half), one timing per rung,
        and caps that stop a line before a rung of more than ~0.1 s. It shows the same
        lines as the full report, with few points each; `make report` gives the full one."""
        full = Config()
        thin = lambda ladder: thin_ladder(ladder, rungs)
        return replace(
            full,
            scenes=tuple(scenes),
            fmu_theta={m: thin(ladder) for m, ladder in full.fmu_theta.items()},
            fmu_theta_default=thin(full.fmu_theta_default or ()),
            # Exudyn's explicit step solvers only (the implicit ones on the jointed tops cost
            # seconds a run: 12 of the short report's 46 s of CPU), their ladders whole here:
            # batch.exudyn_ladder cuts them to `rungs`
            exudyn_theta={m: ladder for m, ladder in full.exudyn_theta.items() if m not in EXUDYN_IMPLICIT},
            # scipy's finest tolerances cost seconds each (Python right-hand side): its coarser half
            dopri_tol=thin(full.dopri_tol[: len(full.dopri_tol) // 2 + 1]),
            scipy_rtol={m: thin(ladder[: len(ladder) // 2 + 1]) for m, ladder in full.scipy_rtol.items()},
            cap_fmu=0.1,
            cap_exudyn=0.2,
            cap_scipy=0.2,
            max_repeats=1,
            short_rungs=rungs,
            batch_stop_time=dict(SHORT_STOP_TIME),
        )

    @staticmethod
    def quick(scenes: Sequence[str] = ("symmetric_free",)) -> Config:
        """A tiny configuration for smoke tests: seconds, not minutes. Its error-control part
        takes the scenes of `scenes` it can measure (measurable.has_scipy_reference, the rule
        of the full report's default; rbfmu report refuses a scene given with --scenes
        that it cannot measure), no C step cost (bench_scenes empty) and no fast spin."""
        return Config(
            scenes=tuple(scenes),
            fmu_theta={"rk4": pow2(2, 4), "gauss4": pow2(2, 3)},
            fmu_theta_default=None,
            exudyn_theta={"RK44": pow2(2, 3)},
            dopri_tol=(1e-6,),
            scipy_rtol={"DOP853": (1e-6, 1e-8)},
            cap_fmu=0.2,
            cap_exudyn=0.5,
            cap_scipy=0.5,
            max_repeats=2,
            cosim_T=0.1,
            long_steps=100_000,
            long_budget=0.05,
            long_chunks=10,
            bench_scenes=(),
            bench_n_explicit=20_000,
            bench_n_implicit=2_000,
            tolerances=(1e-4, 1e-8),
            tol_scenes=measurable_scenes(scenes),
            tol_cap=0.1,
            spin_rates=(),  # no fast spin: it would build spin_scene's FMU as well
            spin_T=0.1,
            quick_report=True,
        )
