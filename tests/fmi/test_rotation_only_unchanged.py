"""The rotation-only scenes keep exactly their FMI interface: variables, states and model structure of FMI 3.0 and 2.0.

Free flight and the moving pivot (docs/theory.md §7) added states, inputs and outputs,
but only to the scenes that use them. The golden file tests/golden/rotation_only_interface.json
holds, for every shipped scene without translation, moving_pivot, rotors (docs/theory.md §8) or orbit (§9),
the attributes of
each variable and the model structure of its FMI 3.0 modelDescription, and a digest of
the FMI 2.0 ones, as generated before those features existed. The instantiation token
(a build hash), the generation date and the Method enumeration's item list (which grows
with new integrators) are left out: they are not the variables' interface.
Regenerate (only for a deliberate interface change): `python -m tests.fmi.test_rotation_only_unchanged`.
"""

from __future__ import annotations

import hashlib
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from fmu.build.model_description import fmi2_model_description, fmi3_model_description
from modelsrc.model import build_model
from modelsrc.scene import MOTION_FEATURES, list_scenes, load_scene

GOLDEN = Path(__file__).resolve().parent.parent / "golden" / "rotation_only_interface.json"
TOKEN = "{00000000-0000-0000-0000-000000000000}"


def rotation_only_scenes() -> list[str]:
    return [
        n
        for n in list_scenes()
        if not (load_scene(n).features & MOTION_FEATURES or load_scene(n).rotors or load_scene(n).has("orbit"))
    ]


def interface(name: str) -> dict:
    """The variable interface of a scene's FMI 3.0 and 2.0 modelDescriptions (see above)."""
    model = build_model(load_scene(name))
    root3 = ET.fromstring(fmi3_model_description(model, TOKEN))
    variables = [{"tag": el.tag, **el.attrib} for el in root3.find("ModelVariables")]
    structure = [{"tag": el.tag, **el.attrib} for el in root3.find("ModelStructure")]
    units = sorted(el.get("name") for el in root3.find("UnitDefinitions"))
    root2 = ET.fromstring(fmi2_model_description(model, TOKEN))
    fmi2 = ET.tostring(root2.find("ModelVariables")) + ET.tostring(root2.find("ModelStructure"))
    return {
        "fmi3_variables": variables,
        "fmi3_structure": structure,
        "units": units,
        "fmi2_digest": hashlib.sha256(fmi2).hexdigest(),
    }


@pytest.mark.parametrize("name", rotation_only_scenes())
def test_rotation_only_interface_is_unchanged(name):
    golden = json.loads(GOLDEN.read_text())
    assert name in golden, f"{name}: no golden interface (a new rotation-only scene: regenerate, see the docstring)"
    now, then = interface(name), golden[name]
    for key in ("fmi3_variables", "fmi3_structure", "units"):
        assert now[key] == then[key], (name, key, [a for a, b in zip(now[key], then[key]) if a != b][:3])
    assert now["fmi2_digest"] == then["fmi2_digest"], f"{name}: the FMI 2.0 variables or structure changed"


def test_the_golden_file_covers_every_rotation_only_scene():
    assert sorted(json.loads(GOLDEN.read_text())) == sorted(rotation_only_scenes())


if __name__ == "__main__":  # regenerate the golden file
    GOLDEN.parent.mkdir(exist_ok=True)
    GOLDEN.write_text(json.dumps({n: interface(n) for n in rotation_only_scenes()}, indent=1) + "\n")
    sys.exit(0)
