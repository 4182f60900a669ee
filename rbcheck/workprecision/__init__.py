"""Work-precision report: error against run time of the FMU's integrators and of the baselines (Exudyn, scipy).

``python -m rbcheck.workprecision`` (or ``rbfmu report``) regenerates everything in one
run and writes report.md with PNG diagrams to ``out/report`` (``--out DIR``; ``make
report-docs`` writes the committed docs/report/). A progress bar goes to stderr, the total
time to stdout.

What is measured (the report repeats these definitions):

* error at the end time T of a run, against a reference: e_ω = ‖ω_run(T) − ω_ref(T)‖∞
  (rad/s, body frame), e_R = angle of R_runᵀ R_ref (rad, the geodesic distance on SO(3)),
  and the dimensionless headline error e = max(e_ω / Ω, e_R) with Ω = max_k ‖ω_ref(t_k)‖∞
  over the communication points (rad/s);
* invariant drift, maximum over the communication points: relative E (E_kin of a free
  body, E_total of the heavy top), relative |L_world| (free body) or L_world·e_z (heavy
  top: p_φ, docs/theory.md §4.2), and ||q| − 1|;
* wall time of the integration loop only (no FMU loading, no model assembly), median of
  repeats taken in the same run.

References (docs/theory.md §2.3, §4.2): the closed forms of rbcheck.closed_forms.free_symmetric,
rbcheck.closed_forms.free_asymmetric, rbcheck.closed_forms.heavy_top where they apply, else scipy DOP853 at
rtol = 3e-14, atol = 1e-16 on the numpy equations of rbcheck.baselines.rigid_body.

Modules, one job each: ``config`` (ladders, caps, levels, targets), ``measures`` (runs,
lines, time at an error level, fastest-method table, orders), ``references`` (reference
solutions, errors, drifts), ``harness`` (timing, guarded child processes, the FMU driver),
``batch`` (ladders and the batch mode per scene), ``cosim`` (closed-loop co-simulation),
``long_horizon``, ``tolerance`` (error control: error against tolerance, cost against
fixed steps), ``tolerance_defaults`` (fast spin and the scenes at their defaults),
``tolerance_report`` (that part's figure and tables), ``plots``, ``markdown`` and ``cli``
(the entry point; ``--parts tolerance`` runs one part alone). C-level timing lives in
fmu.bench.benchmark.
"""

from __future__ import annotations

from .cli import add_arguments, main, run

__all__ = ["add_arguments", "main", "run"]
