"""The scenes as the report's batch mode runs them: the shipped ones, two rotor scenes given inputs known in advance.

Batch mode gives every tool the inputs in advance, held over each communication step
(harness.FmuDriver), so a scene whose motion comes from an importer's loop or from a
schedule that cannot be held is run in a variant, named in the report's header
(`VARIANTS`, docs/theory.md §8.7):

- reaction_wheel_slew: its PD loop closes in the importer (rbcheck.closed_forms.slew), and without it
  nothing moves. It runs open loop: the loop's motor torques at the exact sampled-data
  solution (rbcheck.closed_forms.slew.open_loop_torques) as tables switching every 0.1 s, so the FMU,
  Exudyn and scipy integrate the very inputs the loop would give.
- quadrotor: its rotor speeds are harmonics, which the driver would hold at their means
  over each step together with the means of their derivatives: Ω held while Ω̇ is not 0,
  a system a jointed rotor (Exudyn's) cannot follow, and given continuously they need the
  FMU's intermediate update, whose Python callbacks would be timed. It runs with constant
  speeds: the scene's at t = π/4 s (±Ω_h + 40 rad/s: the drag yaws it) with rotor 1 at
  +2 and rotor 3 at −2 rad/s more (their thrust pitches it), so it turns about all three axes.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from modelsrc.scene import Scene, load_scene

from ..closed_forms.slew import SLEW_GAINS, open_loop_torques

__all__ = ["VARIANTS", "report_scene"]


def _slew_open_loop(sc: Scene) -> Scene:
    n = round(sc.stop_time / sc.step)
    return dataclasses.replace(sc, inputs=open_loop_torques(sc, *SLEW_GAINS, sc.step, n))


QUAD_TIME = math.pi / 4  # s: the scene's speeds then, ±Ω_h + 40 rad/s (the differential δ at its peak)
QUAD_TILT = 2.0  # rad/s: more on the first rotor, less on the third


def _quadrotor_constant(sc: Scene) -> Scene:
    names = list(sc.rotors)
    speeds = {f"Omega_{n}": float(sc.input_at(f"Omega_{n}", QUAD_TIME)[0]) for n in names}
    speeds[f"Omega_{names[0]}"] += QUAD_TILT
    speeds[f"Omega_{names[2]}"] -= QUAD_TILT
    return sc.with_inputs_held(speeds)


# scene name -> (variant, what the report's header says about it)
VARIANTS: dict[str, tuple[Callable[[Scene], Scene], str]] = {
    "reaction_wheel_slew": (
        _slew_open_loop,
        "open loop: the PD loop's motor torques at its exact sampled-data solution "
        "(rbcheck.closed_forms.slew) as tables "
        "switching every 0.1 s (batch inputs are known in advance; the loop itself is checked in `rbfmu check`)",
    ),
    "quadrotor": (
        _quadrotor_constant,
        f"constant rotor speeds: the scene's at t = π/4 s (±Ω_h + 40 rad/s) with rotor 1 +{QUAD_TILT:g} and "
        f"rotor 3 −{QUAD_TILT:g} rad/s more, so it yaws and pitches (harmonic speeds held over a step are Ω "
        "held while Ω̇ is not 0, which a jointed rotor cannot follow; the scene's own run is checked against "
        "Exudyn in `rbfmu check`)",
    ),
}


def report_scene(name: str) -> Scene:
    """The scene `name` as batch mode runs it: the shipped one, or its variant (VARIANTS)."""
    sc = load_scene(name)
    variant = VARIANTS.get(name)
    return variant[0](sc) if variant else sc
