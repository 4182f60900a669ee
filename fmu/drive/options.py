"""Values of command-line options shared by the subcommands of `rbfmu`: NAME=VALUE pairs, numbers, methods.

`split_assignment` is the one reader of NAME=VALUE (`--set`, the sweep's `--param` and
`--sample`); numbers are checked by modelsrc.errors.finite_number and methods by
modelsrc.methods.enumeration_value, so every option refuses a bad value with the same words;
a value almost surely given in the wrong unit is warned about (modelsrc.unit_mistakes).
"""

from __future__ import annotations

from collections.abc import Sequence

from modelsrc import unit_mistakes
from modelsrc.errors import ModelInputError, finite_number
from modelsrc.methods import METHODS, enumeration_value


def split_assignment(text: str, option: str, example: str) -> tuple[str, str, str]:
    """(NAME, VALUE, where) of an option value NAME=VALUE, both stripped; `where` names the
    option and the text for messages. Refuses a missing '=', name or value, showing `example`."""
    name, sep, rest = text.partition("=")
    where = f"{option} {text!r}"
    if not sep or not name.strip() or not rest.strip():
        raise ModelInputError(f"{where}: expected {example}")
    return name.strip(), rest.strip(), where


def parse_set(items: Sequence[str]) -> dict[str, float]:
    """--set NAME=VALUE items -> {name: value}; `method` also takes a method name. Warns
    (ModelInputWarning) for a value almost surely given in the wrong unit."""
    values: dict[str, float] = {}
    for item in items:
        name, val, where = split_assignment(item, "--set", "NAME=VALUE, e.g. --set 'w_body[3]=200'")
        if name in values:  # the earlier value would be dropped without a word
            raise ModelInputError(f"{where}: {name} is set twice; give each name once")
        if name == "method":
            v = enumeration_value(val, {m.name: m.value for m in METHODS.values()})
            if v is None:
                allowed = ", ".join(f"{m.value} = {m.name}" for m in METHODS.values())
                raise ModelInputError(f"{where}: method must be a method name or its value ({allowed})")
            values["method"] = v
            continue
        values[name] = finite_number(val, where)
        unit_mistakes.start_value(name, name, values[name])  # the words of run_fmu's warning: printed once
    return values


def positive_int(text: str, option: str) -> int:
    """The whole number >= 1 that `option` was given as text, else ModelInputError naming it."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise ModelInputError(f"{option}: {text!r} is not allowed: give a whole number >= 1")
    return value
