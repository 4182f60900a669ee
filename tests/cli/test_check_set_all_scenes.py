"""rbfmu check --set is checked against every scene asked for before any check runs.

Before, `check --scene torque_driven --scene symmetric_free --set 'tau_body[1]=0.1'` ran
torque_driven's whole check, then refused the value for symmetric_free with "(this scene's
inputs: none)", without naming the scene.
"""

from __future__ import annotations

from fmu.cli import main


def test_a_set_one_scene_cannot_take_is_refused_before_any_check(capsys):
    code = main(["check", "--scene", "torque_driven", "--scene", "symmetric_free", "--set", "tau_body[1]=0.1"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""  # no table printed: nothing ran
    assert "scene symmetric_free's inputs: none" in err
