"""How much a scene may ask for: the limits that keep its load, build and runs bounded in time.

The one place for a scene's size limits (load_scene and build_fmu check them; a new
kind of repeated element, such as rotors, gets its limit here). Measured on this
project's 2-core machine under a load of about 8 (docs/robustness.md §5, issue 23 item 6):

- Force points: each adds an input and a parameter vector, and every method's step
  repeats the right-hand side that sums their forces and torques, so the generated C and
  gcc's time grow with their number. `rbfmu build --platforms host` of the spacecraft
  with 1, 8, 16, 32 force points: model_funcs.c 0.72, 1.15, 1.52, 2.34 MB; build
  31, 41, 105, 345 s (1 : 1.3 : 3.4 : 11). 2,000 points gave a 113 MB file that gcc had
  not compiled after 900 s. The limit, 16, keeps a build within about 3.5 times that of
  one point; 32 already costs 11 times.
- Rotors (docs/theory.md §8): each adds a state, an input and a parameter, and its terms
  to every right-hand side; the Jacobian's size grows with the square of the states.
  Generated instructions with 1, 4, 8, 16 rotors (random axes): right-hand side 109, 190,
  298, 514; RK4 step 505, 832, 1268, 2140; Jacobian 983, 1871, 3559, 8663. `build_fmu`
  (host binary) of 1 and 16 rotors: 19 s and 85 s (1 : 4.4, the machine loaded by a test
  run). The limit, 16, matches the force points' and covers every spacecraft and
  multirotor of issue 28 (three or four wheels, four rotors).
- Input-table rows: each row is a switching time, so a communication point of every run
  and of the build's check; reading 1e4 rows took 0.58 s, 1e5 rows 7.7 s (the scene file
  limit, 16 MiB, allows about 4e5).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .errors import ModelInputError
from .scene_reader import SceneReader

MAX_FORCE_POINTS = 16
MAX_ROTORS = 16
MAX_TABLE_ROWS = 100_000


def check_scene_limits(path: Path | str | None, force_points: int, inputs: Mapping[str, Any], rotors: int = 0) -> None:
    """ModelInputError naming the scene file, the count and the limit when a scene (its
    number of force points, its input schedules by name, its number of rotors) asks for
    more force points, input-table rows or rotors than the limits allow."""
    where = f"scene file {path}"
    if rotors > MAX_ROTORS:
        raise ModelInputError(
            f"{where}: field 'rotors': {rotors} rotors; at most {MAX_ROTORS} are allowed (each adds a state, an "
            "input and a parameter to every method's step, and the build time grows with them)"
        )
    n = force_points
    if n > MAX_FORCE_POINTS:
        raise ModelInputError(
            f"{where}: field 'forces': {n} force points; at most {MAX_FORCE_POINTS} are allowed (the generated "
            "code and its compile time grow with each: 32 points build 11 times slower than one)"
        )
    for name, spec in inputs.items():
        rows = int(getattr(spec, "shape", (0,))[0]) if getattr(spec, "ndim", 0) == 2 else 0
        if rows > MAX_TABLE_ROWS:
            raise ModelInputError(f"{where}: field 'inputs.{name}': {_too_many_rows(rows)}")


def check_table_rows(rd: SceneReader, fld: str, value: Any) -> None:
    """Refuse an input table of more than MAX_TABLE_ROWS rows as it is read, before its
    rows are checked one by one (a list of lists: a table; other inputs pass)."""
    if isinstance(value, list) and len(value) > MAX_TABLE_ROWS and isinstance(value[0], list):
        raise rd.fail(fld, _too_many_rows(len(value)))


def _too_many_rows(rows: int) -> str:
    return f"{rows} table rows; at most {MAX_TABLE_ROWS} are allowed (each row is a communication point of every run)"
