"""A linear model with named states, inputs and outputs: ẋ = A x + B u, y = C x + D u, or its discrete map.

The matrices are the deviations from an operating point. `scipy.signal.StateSpace(*m)`
and `control.ss(*m)` accept the model as it is (it unpacks to A, B, C, D; a discrete one
carries its step in `dt`), and `to_scipy()`, `to_control()` make those objects with the
step and (python-control) the names.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import MISSING, dataclass, field, fields, replace

import numpy as np

from modelsrc.errors import ModelInputError, unknown_variable

from .operating_point import OperatingPoint


@dataclass(frozen=True)
class LinearModel:
    """A, B, C, D with names. coordinates: "raw" (the FMU's states) or "attitude error"
    (docs/theory.md §10); frame: the attitude reference, "rotating" or "fixed" (raw: "");
    drift: ẋ (or ż) at the point, 0 at an equilibrium (a relative one in the rotating
    frame): a linearisation about a point that is not one has the affine term drift;
    dt: None for ẋ = A x + B u, the step (s) for x[k+1] = A x[k] + B u[k]; point: the
    operating point; method, substeps: the integrator and its internal steps per dt of a
    discrete map; nominals: a scale per state (the FMU's nominal values; 1 rad for δθ)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    point: OperatingPoint
    coordinates: str = "raw"
    frame: str = ""
    drift: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dt: float | None = None
    method: str = ""
    substeps: int = 0
    nominals: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @staticmethod
    def fields_with(**fixed) -> dict:
        """The defaults of the fields with these values: every field but those of `made_with`'s
        arguments (A, B, C, D, point, drift), made once for what stays from one model to the
        next (a linearisation's names, coordinates and nominals, kept in its plan). TypeError
        for an unknown field or one missing. (A frozen dataclass's __init__ sets each of its
        15 fields through object.__setattr__: 4 µs of a 30 µs linearisation, fmu.linear.bench.)"""
        d = _DEFAULTS | fixed
        if d.keys() != _FIELDS - _PER_MODEL:
            missing, unknown = sorted(_FIELDS - _PER_MODEL - d.keys()), sorted(d.keys() - (_FIELDS - _PER_MODEL))
            raise TypeError(f"LinearModel.fields_with: fields missing {missing}, unknown {unknown}")
        return d

    @classmethod
    def made_with(cls, fixed: dict, A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray,
                  point: OperatingPoint, drift: np.ndarray) -> LinearModel:  # fmt: skip
        """The model of the fields `fixed` (from `fields_with`, not changed) and these six, made
        without the dataclass's __init__: the instance's dict filled at once (`fields_with`
        checked the rest of the fields)."""
        m = object.__new__(cls)
        d = m.__dict__
        d.update(fixed)
        d["A"], d["B"], d["C"], d["D"], d["point"], d["drift"] = A, B, C, D, point, drift
        return m

    def __iter__(self) -> Iterator[np.ndarray]:
        """A, B, C, D, as scipy.signal.StateSpace(*m) and control.ss(*m) take them."""
        return iter((self.A, self.B, self.C, self.D))

    def to_scipy(self):
        """scipy.signal.StateSpace of the model (discrete with dt = the step)."""
        from scipy import signal

        if self.dt is None:
            return signal.StateSpace(self.A, self.B, self.C, self.D)
        return signal.StateSpace(self.A, self.B, self.C, self.D, dt=self.dt)

    def to_control(self):
        """python-control's StateSpace with the names (the package `control`, not a
        dependency of rbfmu: ModelInputError saying how to get it when it is missing)."""
        try:
            import control
        except ImportError:
            raise ModelInputError("to_control needs python-control: pip install control") from None
        kw = {"dt": self.dt} if self.dt is not None else {}
        return control.ss(self.A, self.B, self.C, self.D, states=list(self.states), inputs=list(self.inputs),
                          outputs=list(self.outputs), **kw)  # fmt: skip

    def select(
        self,
        states: Sequence[str] | None = None,
        inputs: Sequence[str] | None = None,
        outputs: Sequence[str] | None = None,
    ) -> LinearModel:
        """The model of some of the states, inputs and outputs (None: all). States may be
        left out only when they do not act on the kept ones (their columns of A are 0 in
        the kept rows, and of C in the kept outputs): otherwise the smaller model would be
        wrong, and ModelInputError names the coupling."""
        ks = self._pick(states, self.states, "states")
        ki = self._pick(inputs, self.inputs, "inputs")
        ko = self._pick(outputs, self.outputs, "outputs")
        dropped = [k for k in range(len(self.states)) if k not in ks]
        for rows, M, what in ((ks, self.A, "state"), (ko, self.C, "output")):
            if dropped and rows:
                sub = M[np.ix_(rows, dropped)]
                if np.any(sub != 0):
                    i, j = np.argwhere(sub != 0)[0]
                    name = (self.states if what == "state" else self.outputs)[rows[i]]
                    raise ModelInputError(
                        f"the state {self.states[dropped[j]]} acts on the {what} {name} (entry {sub[i, j]:.3g}): "
                        "it cannot be left out of the model"
                    )
        return replace(
            self,
            A=self.A[np.ix_(ks, ks)],
            B=self.B[np.ix_(ks, ki)],
            C=self.C[np.ix_(ko, ks)],
            D=self.D[np.ix_(ko, ki)],
            states=tuple(self.states[k] for k in ks),
            inputs=tuple(self.inputs[k] for k in ki),
            outputs=tuple(self.outputs[k] for k in ko),
            drift=self.drift[ks] if len(self.drift) else self.drift,
            nominals=self.nominals[ks] if len(self.nominals) else self.nominals,
        )

    @staticmethod
    def _pick(names: Sequence[str] | None, have: tuple[str, ...], what: str) -> list[int]:
        if names is None:
            return list(range(len(have)))
        for n in names:
            if n not in have:
                raise unknown_variable(n, have, listed=f"{what} of the model")
        return [have.index(n) for n in names]

    def eigenvalues(self) -> np.ndarray:
        """The eigenvalues of A (for a discrete map: of Φ)."""
        return np.linalg.eigvals(self.A)


# LinearModel.fields_with: the fields, and the defaults it fills in (those without a factory: the
# fields with one are given by its callers)
_FIELDS = frozenset(f.name for f in fields(LinearModel))
_DEFAULTS = {f.name: f.default for f in fields(LinearModel) if f.default is not MISSING}
_PER_MODEL = frozenset(("A", "B", "C", "D", "point", "drift"))  # LinearModel.made_with's arguments
