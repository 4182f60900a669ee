"""The input balances' convergence check shared by the tests of `rbfmu check`: Simpson's rule on halving the step."""

from __future__ import annotations

# The input balances of rbcheck.checks.balances as `rbfmu check` names its rows, with the
# attribute of balances()' result that holds each.
BALANCE_ROWS = (
    ("work balance |dE_total - int P dt|", "work"),
    ("momentum balance |dp - int (F + M g) dt|", "momentum"),
    ("ang. momentum balance |dL - int tau dt|", "angular_momentum"),
)


def assert_balances_fall_as_simpson(rows: dict[str, float], half: object) -> None:
    """Each balance residual of a check (rows: quantity -> value at the communication step H)
    against the same balance at H/2 (`half`, rbcheck.checks.balances' result): Simpson's rule
    per step (H⁵|f⁗|/2880) divides it by ~16 on halving H; 12..20 leaves room for the
    higher-order terms and fails on a first- or second-order booking (2 or 4)."""
    for name, attr in BALANCE_ROWS:
        fine = getattr(half, attr)
        assert 12.0 < rows[name] / fine < 20.0, (name, rows[name], fine)
