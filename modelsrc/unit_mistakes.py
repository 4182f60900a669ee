"""Values almost surely given in the wrong unit: warnings that name the value and its likely intent.

Each check warns (modelsrc.errors.ModelInputWarning) and never refuses: the value is
allowed, the run goes on as asked. The scene reader checks a scene file's fields
(`start_angles` for initial.euler_zxz, `orbit_rate` for [orbit] rate); the driver checks the
values a run sets by name (`start_value`: n_orbit, orbit_angle), for `rbfmu run --set` and
fmu.drive.run.run_fmu's start_values alike. docs/user_guide.md §2.4 lists the rules.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence

from .errors import ModelInputWarning

# The fastest circular orbit around a homogeneous sphere of density ρ skims its surface:
# n² = G M / R³ = (4π/3) G ρ (Kepler's third law at r = R), independent of the size. The
# densest element at normal conditions (osmium, ρ = 22 590 kg/m³) gives n = 2.5e-3 rad/s
# (a 42-min period); Earth (5514 kg/m³) 1.24e-3 rad/s (84 min). A rate above
# ORBIT_RATE_MAX (a period under 10.5 min, 4x osmium's bound: 16x its density) is no orbit
# around any planet or moon; a white dwarf or neutron star is not what this tool models.
GRAVITATIONAL_CONSTANT = 6.674e-11  # m³/(kg·s²), CODATA 2018
DENSEST_BODY = 22_590.0  # kg/m³, osmium
SURFACE_ORBIT_RATE = math.sqrt(4.0 * math.pi / 3.0 * GRAVITATIONAL_CONSTANT * DENSEST_BODY)  # 2.513e-3 rad/s
ORBIT_RATE_MAX = 0.01  # rad/s
# The slowest rate a reading of the number may give to be offered (rad/s, a period of two years).
ORBIT_RATE_MIN = 1e-7
# A full turn: an angle beyond it is legal (the same attitude) but is almost surely degrees.
FULL_TURN = 2.0 * math.pi
# The units a number given for the orbit rate may have been meant in, as a conversion of the
# number v to rad/s; a reading is offered as the likely intent where it gives a possible rate
# (between ORBIT_RATE_MIN and SURFACE_ORBIT_RATE).
_RATE_READINGS = (
    ("an orbital period in s", lambda v: FULL_TURN / v, "2 pi / {v:g} s"),
    ("an orbital period in min", lambda v: FULL_TURN / (60.0 * v), "2 pi / ({v:g} x 60 s)"),
    ("a mean motion in rev/day", lambda v: FULL_TURN * v / 86_400.0, "{v:g} x 2 pi / 86400 s"),
    ("a rate in deg/s", lambda v: math.radians(v), "{v:g} x pi / 180"),
)


def warn(message: str) -> None:
    """Issue `message` as a ModelInputWarning, attributed to the caller's caller."""
    warnings.warn(message, ModelInputWarning, stacklevel=3)


def start_angles(where: str, angles: Sequence[float]) -> None:
    """Warn when an angle of a start attitude (rad, e.g. initial.euler_zxz) exceeds a full
    turn in magnitude: legal, but [0, 30, 0] is almost surely 30 degrees, not 30 rad."""
    big = [a for a in angles if abs(a) > FULL_TURN]
    if big:
        shown = ", ".join(f"{a:g}" for a in angles)
        radians = ", ".join(f"{math.radians(a):.6g}" for a in angles)
        warn(
            f"{where} = [{shown}]: {big[0]:g} is more than a full turn (2 pi = 6.2832 rad); the angles are in rad: "
            f"if degrees were meant, give [{radians}]"
        )


def angle(where: str, value: float) -> None:
    """Warn when one angle (rad, e.g. the start orbit_angle) exceeds a full turn in magnitude."""
    if abs(value) > FULL_TURN:
        warn(
            f"{where} = {value:g} rad is more than a full turn (2 pi = 6.2832 rad): if degrees were meant, "
            f"give {math.radians(value):.6g}"
        )


def orbit_rate(where: str, n: float) -> None:
    """Warn when an orbit rate n (rad/s) exceeds ORBIT_RATE_MAX, faster than any circular
    orbit around a planet, naming the readings of the number that give a possible rate (a
    period given as the rate, `[orbit] rate = 5677`, reads as 2 pi / 5677 s)."""
    if not n > ORBIT_RATE_MAX:
        return
    likely = [
        f"{what} ({formula.format(v=n)} = {to_rate(n):.5g} rad/s)"
        for what, to_rate, formula in _RATE_READINGS
        if ORBIT_RATE_MIN <= to_rate(n) <= SURFACE_ORBIT_RATE
    ]
    intent = f"; it reads like {' or '.join(likely[:2])}" if likely else ""
    warn(
        f"{where} = {n:g} rad/s is an orbital period of {FULL_TURN / n:.3g} s: no circular orbit around a planet "
        f"turns faster than {ORBIT_RATE_MAX:g} rad/s (a period of {FULL_TURN / ORBIT_RATE_MAX / 60:.1f} min; low "
        f"Earth orbit: about 1.1e-3 rad/s){intent}; the rate is n = 2 pi / period, in rad/s"
    )


# The FMU variables a run may set whose value is checked here: name -> the check.
START_VALUE_CHECKS = {"n_orbit": orbit_rate, "orbit_angle": angle}


def start_value(where: str, name: str, value: float) -> None:
    """Warn for a start value or parameter set by name (rbfmu run --set, run_fmu's
    start_values) that is almost surely a unit mistake; other names are not checked."""
    check = START_VALUE_CHECKS.get(name)
    if check is not None:
        check(where, value)
