"""Alias until 0.5.0 (CHANGELOG.md): the code lives in rbcheck/numerics/motion_fits.py."""

from rbcheck.numerics.motion_fits import (
    GrowthFit,
    cos_tilt,
    crossing_times,
    figure_axis_world,
    first_exceedance,
    fit_exponential_growth,
    interp_cubic,
    loglog_slope,
    mean_period,
    phase_rate,
    precession_angle,
    refined_extrema,
    rotation_rate_about,
    tilt_angle,
)

__all__ = [
    "GrowthFit",
    "cos_tilt",
    "crossing_times",
    "figure_axis_world",
    "first_exceedance",
    "fit_exponential_growth",
    "interp_cubic",
    "loglog_slope",
    "mean_period",
    "phase_rate",
    "precession_angle",
    "refined_extrema",
    "rotation_rate_about",
    "tilt_angle",
]
