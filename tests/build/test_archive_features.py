"""documentation/index.html states each scene's features, equations and conserved quantities (issue 34 item 2).

The page is written from the feature units the model is built from (`Feature.doc`,
modelsrc.registry.feature_docs, conserved_quantities): checked on every shipped scene and on
user scenes with rotors, an orbit and a central field (index_html on the built model; no FMU
is compiled here).
"""

from __future__ import annotations

import html
import re

import pytest

from fmu.build.archive_docs import index_html
from fmu.build.build_check import BuildCheck
from modelsrc.model import build_model
from modelsrc.registry import conserved_quantities, feature_docs
from modelsrc.scene import list_scenes, load_scene

from ..harness.scenes import write_scene

HOST = "x86_64-linux"


def _text(page: str) -> str:
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", page)))


def _section(text: str, head: str, next_head: str) -> str:
    return text[text.index(head) + len(head) : text.index(next_head)]


def _page(scene, check: BuildCheck | None = None) -> str:
    return _text(index_html(build_model(scene), "3", [HOST], HOST, check))


def _check_page(scene) -> str:
    text = _page(scene)
    docs = feature_docs(scene)
    features = _section(text, " features ", " inertia about")
    if docs:  # every feature the model is built with, none left out
        assert "none" not in features, features
        for name, d in docs:
            assert f"{name}: {d.summary}" in features
    else:
        assert features.strip().startswith("none: a free rigid body")
    equations = _section(text, "Equations", "Conserved quantities")
    for _, d in docs:
        for eq, _src in d.equations:
            assert _text(html.escape(eq)) in equations, eq
    conserved = _section(text, "Conserved quantities", "Variables")
    kept = conserved_quantities(scene)
    for k in kept:
        assert k in conserved
    if not kept:
        assert conserved.strip().startswith("None:")
    return conserved


@pytest.mark.parametrize("name", list_scenes())
def test_every_shipped_scene_states_its_features_equations_and_invariants(name):
    sc = load_scene(name)
    conserved = _check_page(sc)
    if sc.has("orbit"):
        assert "E_jacobi" in conserved  # not "drift of E: not conserved" with nothing else
    if sc.has("central_gravity"):
        assert "L_total" in conserved
    if sc.rotors:
        assert "J Ω̇ = u − J g·ω̇" in _page(sc) or all(r.speed for r in sc.rotors.values())


PYRAMID = """
name = "pyramid"
description = "four wheels in a pyramid"
outputs = ["q", "w_body", "E_kin", "L_world"]
[body]
principal_moments = [10.0, 12.0, 8.0]
[initial]
w_body = [0.01, 0.0, 0.0]
q = [1.0, 0.0, 0.0, 0.0]
"""
C = 3**-0.5  # the four axes of a pyramid, unit vectors to the last bit
for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
    PYRAMID += f"[rotors.w{k + 1}]\naxis = [{sx * C!r}, {sy * C!r}, {C!r}]\nJ = 0.02\n"

ORBIT_WHEEL = """
name = "my_orbit_sat"
description = "a wheel along the orbit normal"
outputs = ["q", "w_body"]
[features]
orbit = true
gravity_gradient = true
[orbit]
rate = 0.0011
[body]
principal_moments = [120.0, 100.0, 80.0]
[rotors.wheel]
axis = [0.0, -1.0, 0.0]
J = 0.05
[initial]
w_body = [0.0, -0.0011, 0.0]
q = [1.0, 0.0, 0.0, 0.0]
Omega_wheel = 300.0
"""


def test_user_scenes_with_rotors_orbit_and_central_field(tmp_path):
    pyramid = load_scene(write_scene(tmp_path, PYRAMID, "pyramid"))
    conserved = _check_page(pyramid)
    text = _page(pyramid)
    assert "features none" not in text and "rotors: rotors (a gyrostat): w1 (torque mode)" in text
    assert "speed mode" not in _section(text, "Equations", "Conserved quantities")  # no equation it does not use
    assert "L_world" in conserved
    orbit = load_scene(write_scene(tmp_path, ORBIT_WHEEL, "my_orbit_sat"))
    assert "E_jacobi" in _check_page(orbit)
    central_text = (load_scene("eccentric_orbit").path.read_text()).replace('"eccentric_orbit"', '"my_kepler"')
    central = load_scene(write_scene(tmp_path, central_text, "my_kepler"))
    assert "L_total" in _check_page(central)


def test_an_exact_zero_is_not_a_figure_a_tolerance_is_compared_with():
    sc = load_scene("gravity_gradient_boom")
    zero = BuildCheck("rk8", "rk8", "tolerance 1e-10 1/s", "tolerance 1e-13 1/s", 10.0, 16200.0,
                      w_diff=0.0, q_diff=0.0, w_scale=1e-3, qnorm=0.0, E_drift=None, L_drift=None, wall_s=0.1)  # fmt: skip
    validation = _section(_page(sc, zero), "Validation measured for this scene", "Platforms")
    assert "0.00e+00" not in validation and "0 exactly" in validation
    assert "in an orbit E_jacobi is" in validation
