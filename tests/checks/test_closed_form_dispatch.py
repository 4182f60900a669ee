"""One dispatcher says which closed form gives a scene's rotation, for the checks and the report alike.

Before, rbcheck.checks.generic.closed_form_trajectory and
rbcheck.workprecision.references.closed_form each had their own copy of the rules (the held
rate, the free bodies, the Lagrange top), which had to be changed together. Now both ask
rbcheck.closed_forms.of_scene.closed_rotation; the report adds one rule of its own, that a
body in free flight needs its centre of mass on the parabola (only uniform gravity on it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from modelsrc.scene import list_scenes, load_scene
from rbcheck.checks.common import NotApplicable
from rbcheck.checks.generic import closed_form_trajectory
from rbcheck.closed_forms import free_asymmetric
from rbcheck.closed_forms.of_scene import NoClosedForm, closed_rotation, parabola_applies
from rbcheck.workprecision.references import closed_form

T = np.linspace(0.0, 0.5, 6)
# the closed form of each shipped scene that has one (module name); the others have none
EXPECTED = {
    "free_asymmetric": "free_asymmetric",
    "heavy_top": "heavy_top",
    "skewed_bar": "uniform_rotation",
    "symmetric_free": "free_symmetric",
    "thrown_racket": "free_asymmetric",
    "two_frame_arm": "free_symmetric",
}


@pytest.mark.parametrize("name", list_scenes())
def test_the_check_and_the_report_ask_one_dispatcher(name):
    scene = load_scene(name)
    want = EXPECTED.get(name)
    report = closed_form(scene, T)
    if want is None:
        with pytest.raises(NotApplicable):
            closed_form_trajectory(scene, T)
        with pytest.raises(NoClosedForm):
            closed_rotation(scene, T)
        assert report is None
        return
    w, q, label = closed_form_trajectory(scene, T)
    cr = closed_rotation(scene, T)
    assert f"rbcheck.closed_forms.{want}" in cr.name and label == f"closed form: {cr.name}"
    assert report is not None and report[2] == f"closed form {cr.name}"
    for a, b in ((w, cr.w), (q, cr.q), (report[0], cr.w), (report[1], cr.q)):
        assert np.array_equal(a, b)


def _racket(tmp_path: Path, extra_features: str, extra: str = "") -> Path:
    text = (Path("modelsrc/scenes/thrown_racket.toml")).read_text()
    text = text.replace('name = "thrown_racket"', 'name = "forced_racket"')
    text = text.replace("gravity = true\n", f"gravity = true\n{extra_features}", 1)
    path = tmp_path / "forced_racket.toml"
    path.write_text(text + extra)
    return path


def test_a_forced_body_in_flight_keeps_its_rotation_but_not_its_parabola(tmp_path):
    # a force at the centre of mass puts no torque on the body: its rotation is still Jacobi's,
    # which the check uses; its centre of mass leaves the parabola, so the report takes scipy
    scene = load_scene(str(_racket(tmp_path, "force_world = true\n", "\n[inputs]\nf_world = [1.0, 0.0, 0.0]\n")))
    assert scene.torque_free and not parabola_applies(scene)
    w, q, label = closed_form_trajectory(scene, T)
    assert label == "closed form: rbcheck.closed_forms.free_asymmetric"
    I = np.diag(np.asarray(scene.inertia, dtype=float))
    w_cf, q_cf = free_asymmetric.solve(I, scene.w0, scene.q0, T)
    assert np.array_equal(w, w_cf) and np.array_equal(q, q_cf)
    assert closed_form(scene, T) is None
    plain = load_scene("thrown_racket")
    assert parabola_applies(plain) and closed_form(plain, T) is not None


def test_the_reasons_are_said():
    with pytest.raises(NoClosedForm, match="rotors"):
        closed_rotation(load_scene("dual_spin"), T)
    with pytest.raises(NoClosedForm, match=r"torques act \(friction, gravity\)"):
        closed_rotation(load_scene("sleeping_top"), T)
    with pytest.raises(NotApplicable, match="central_gravity"):
        closed_form_trajectory(load_scene("eccentric_orbit"), T)
