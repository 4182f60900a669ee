"""Linear models on disk: A, B, C, D with their names as .npz (numpy) and .json (any language), checked before writing.

`check_output` refuses a bad path before anything is computed (so that bad input writes
nothing); `write` puts both files next to each other (FILE.npz and FILE.json), each through
a temporary file renamed into place, so that there is never half a file; `load` reads the
.npz back.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from modelsrc.errors import ModelInputError

from .eigen import modes
from .linear_model import LinearModel
from .operating_point import OperatingPoint


def check_output(path: str | Path) -> Path:
    """The .npz path of --out, checked: suffix .npz, not a directory, in a folder that exists
    (ModelInputError naming it). The .json goes beside it."""
    p = Path(path)
    if p.suffix != ".npz":
        raise ModelInputError(f"--out {path}: give a file name ending in .npz (FILE.json is written beside it)")
    if p.is_dir():
        raise ModelInputError(f"--out {path}: is a directory; give a file name")
    if not p.resolve().parent.is_dir():
        raise ModelInputError(f"--out {path}: the directory {p.parent} does not exist")
    return p


def as_dict(model: LinearModel, scene: str = "") -> dict:
    """Everything of the model as JSON-ready values (complex eigenvalues as [re, im])."""
    ms, how = modes(model)
    pt = model.point
    return {
        "scene": scene,
        "coordinates": model.coordinates,
        "frame": model.frame,
        "dt": model.dt,
        "method": model.method,
        "substeps": model.substeps,
        "states": list(model.states),
        "inputs": list(model.inputs),
        "outputs": list(model.outputs),
        "A": model.A.tolist(),
        "B": model.B.tolist(),
        "C": model.C.tolist(),
        "D": model.D.tolist(),
        "drift": model.drift.tolist(),
        "operating_point": {
            "states": dict(pt.states),
            "inputs": dict(pt.inputs),
            "parameters": dict(pt.parameters),
            "time": pt.time,
            "source": pt.source,
        },
        "modes": [
            {
                "eigenvalue": [m.eigenvalue.real, m.eigenvalue.imag],
                "frequency": m.frequency,
                "damping": None if np.isnan(m.damping) else m.damping,
                "time_constant": None if np.isinf(m.time_constant) else m.time_constant,
                "kind": m.kind,
                "dominant": [[n, s] for n, s in m.dominant],
            }
            for m in ms
        ],
        "dominant_by": how,
    }


def _replace(path: Path, write) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write(model: LinearModel, path: str | Path, scene: str = "") -> tuple[Path, Path]:
    """Write FILE.npz and FILE.json; returns both paths."""
    npz = check_output(path)
    js = npz.with_suffix(".json")
    pt = model.point
    arrays: dict[str, Any] = {
        "A": model.A, "B": model.B, "C": model.C, "D": model.D,
        "states": np.array(model.states, dtype=str), "inputs": np.array(model.inputs, dtype=str),
        "outputs": np.array(model.outputs, dtype=str), "drift": model.drift, "nominals": model.nominals,
        "x0": pt.x, "x0_names": np.array(list(pt.states), dtype=str), "u0": pt.u,
        "u0_names": np.array(list(pt.inputs), dtype=str), "time": np.array(pt.time),
        "dt": np.array(np.nan if model.dt is None else model.dt),
        "coordinates": np.array(model.coordinates), "frame": np.array(model.frame),
    }  # fmt: skip
    _replace(npz, lambda f: np.savez(f, **arrays))
    text = json.dumps(as_dict(model, scene), indent=1)
    _replace(js, lambda f: f.write(text.encode()))
    return npz, js


def load(path: str | Path) -> LinearModel:
    """A model written by `write` (its operating point without parameters)."""
    with np.load(path) as z:
        dt = float(z["dt"])
        point = OperatingPoint(
            dict(zip(map(str, z["x0_names"]), map(float, z["x0"]))),
            dict(zip(map(str, z["u0_names"]), map(float, z["u0"]))),
            time=float(z["time"]),
            source=f"file {path}",
        )
        return LinearModel(
            A=z["A"], B=z["B"], C=z["C"], D=z["D"], states=tuple(map(str, z["states"])),
            inputs=tuple(map(str, z["inputs"])), outputs=tuple(map(str, z["outputs"])), point=point,
            coordinates=str(z["coordinates"]), frame=str(z["frame"]), drift=z["drift"],
            dt=None if np.isnan(dt) else dt, nominals=z["nominals"],
        )  # fmt: skip
