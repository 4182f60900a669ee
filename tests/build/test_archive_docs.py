"""What an importer shows a person: documentation/index.html and the icon in every FMU, generated from the metadata."""

from __future__ import annotations

import html
import re
import zipfile
from io import BytesIO
from types import SimpleNamespace

import matplotlib.image
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from fmu.build import archive_docs
from fmu.build.archive_docs import frame_of
from fmu.build.build_check import reference_method
from fmu.build.icon import ICON_PIXELS, ellipsoid_axes, icon_features, write_icon
from fmu.build.platforms import host_platform, platforms_for
from modelsrc.methods import METHODS
from modelsrc.scene import list_scenes, load_scene

SCENES = list_scenes()


def _member(fmu, name: str) -> bytes:
    with zipfile.ZipFile(fmu) as z:
        return z.read(name)


def _text(page: str) -> str:
    return html.unescape(re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", page)))


@pytest.mark.parametrize("scene", SCENES)
def test_documentation_lists_every_variable_method_and_equation(fmus, scene):
    page = _member(fmus[scene], "documentation/index.html").decode()
    text = _text(page)
    md = read_model_description(str(fmus[scene]))
    for v in md.modelVariables:  # every variable, with its unit
        assert f" {v.name} " in text, v.name
    items = [(i.name, i.value) for t in md.typeDefinitions for i in t.items]
    for name, value in items:  # every method compiled in, with its enumeration value
        assert f"{value} {name}" in text or f"{value} = {name}" in text, name
    assert "I ω̇ + ω × (I ω) = τ" in text and "§2.1" in text  # Euler's equations and their source
    assert "validation measured for this scene" in text.lower() and "Not measured" not in text
    assert "../terminalsAndIcons/icon.png" in page


@pytest.mark.parametrize("scene", SCENES)
def test_icon_and_documentation_are_in_a_clean_archive(fmus, scene):
    assert validate_fmu(str(fmus[scene])) == []  # documentation/ and terminalsAndIcons/ included
    icon = matplotlib.image.imread(BytesIO(_member(fmus[scene], "terminalsAndIcons/icon.png")), format="png")
    assert icon.shape[:2] == (ICON_PIXELS, ICON_PIXELS)
    assert 0.02 < float(np.mean(icon[..., 3] > 0)) < 0.9  # the body is drawn, on a transparent background


@pytest.mark.slow
def test_fmi2_archive_has_model_png_and_documentation(fmi2_fmus):
    fmu = fmi2_fmus["heavy_top"]
    assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
    assert {"model.png", "documentation/index.html"} <= names and not any(n.startswith("terminals") for n in names)
    assert "../model.png" in _member(fmu, "documentation/index.html").decode()


def test_validation_figures_are_measured_and_plausible(fmus):
    # heavy_top: its defaults (rk8, tolerance 1e-10 per second) against rk8 at a thousandth
    # of the tolerance; E is conserved, L_world is not (gravity). The default run's error
    # over 2 s is ~1e-13 relative (docs/report/report.md, tolerance sweep): the figure must be
    # finite, small (below tolerance·T·|ω| with a margin of 100 for the estimate's
    # pessimism) and not 0
    text = _text(_member(fmus["heavy_top"], "documentation/index.html").decode())
    m = re.search(r"rk8 \(tolerance 1e-10 1/s\) vs rk8 \(tolerance 1e-13 1/s\): .*?∞ ([0-9.e+-]+) rad/s", text)
    assert m, text[:2000]
    assert 0 < float(m.group(1)) < 100 * 1e-10 * 2.0 * 150  # max |ω| = 150 rad/s, T = 2 s
    drift = re.search(r"max relative drift of E ([0-9.e+-]+)", text)
    assert drift and float(drift.group(1)) < 1e-9
    assert "drift of |L_world| not conserved here" in text


def test_reference_method_and_frames():
    assert reference_method(("rk4", "rk8", "gauss6")) == "rk8"
    assert reference_method(("rk4", "gauss6")) == "gauss6"
    assert METHODS["gauss6"].order > METHODS["rk4"].order
    assert frame_of("w_body[1]", "angular velocity, body axis 1") == "body"
    assert frame_of("tau_world[2]", "torque input, world axis 2") == "world"
    assert frame_of("q[1]", "orientation quaternion body->world") == "body → world"


def test_icon_ellipsoid_has_the_inertia_of_the_body():
    # a uniform ellipsoid has I_1 = m (b² + c²)/5: the semi-axes recover the moments' ratios
    semi, axes = ellipsoid_axes(np.diag([1.0, 2.0, 2.5]))
    a, b, c = semi
    moments = np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    assert np.allclose(moments / moments[0], [1.0, 2.0, 2.5])
    assert np.allclose(np.abs(axes), np.eye(3))


def test_body_table_has_a_heading_in_every_column():
    page = archive_docs._body(SimpleNamespace(scene=load_scene("heavy_top")))  # type: ignore[arg-type]
    assert "<th></th>" not in page and page.startswith("<table><tr><th>property</th><th>value</th></tr>")


def test_platform_table_states_the_oldest_system_of_each_binary():
    page = archive_docs._platforms(platforms_for(3), host_platform(), "3")
    assert "glibc 2.17 or newer" in _text(page) and "macOS 11.0 or newer" in _text(page)
    assert page.count("glibc 2.17 or newer") == 2  # x86_64-linux too (zig's, not the build machine's)
    assert "build machine's glibc" in archive_docs._platforms([host_platform()], host_platform(), "3")


def _icon(scene: str, tmp_path) -> bytes:
    path = tmp_path / f"{scene}.png"
    write_icon(load_scene(scene), path)
    return path.read_bytes()


def test_icons_draw_what_the_scene_has(tmp_path):
    drawn = {s: icon_features(load_scene(s)) for s in ("heavy_top", "top_on_shaker", "spacecraft_thruster")}
    assert "shaker" not in drawn["heavy_top"] and "pivot" in drawn["heavy_top"]
    base, motion = drawn["top_on_shaker"]["shaker"]  # the moving pivot's table, its motion along world z
    assert motion is not None and abs(motion[2]) > 0 and np.allclose(motion[:2], 0)
    at, thrust = drawn["spacecraft_thruster"]["force thruster"]  # the thruster fires along body x (q0 = 1)
    assert thrust is not None and thrust[0] > 0 and np.allclose(thrust[1:], 0)
    assert np.allclose(at / np.linalg.norm(at), np.array([0.0, 1.0, 0.3]) / np.linalg.norm([0.0, 1.0, 0.3]))
    assert "sensor" in drawn["spacecraft_thruster"] and "sensor" not in drawn["heavy_top"]
    assert "pivot" not in icon_features(load_scene("thrown_racket"))  # free flight: no pivot
    icons = {s: _icon(s, tmp_path) for s in drawn}
    assert len(set(icons.values())) == 3  # top_on_shaker's was heavy_top's, byte for byte
