"""The FMU's documentation/index.html: the body, its equations and sources, variables, methods, validation.

Generated from the same metadata as the modelDescription (the model's variables,
modelsrc.methods.METHODS, the scene) plus the figures measured at build time
(fmu.build.build_check); an importer shows it to the person who uses the FMU.
"""

from __future__ import annotations

import html
from collections.abc import Sequence

import numpy as np

from modelsrc.methods import DEFAULT_TOLERANCE, METHODS
from modelsrc.model import RigidBodyModel
from modelsrc.registry import conserved_quantities, feature_docs
from modelsrc.variables import Kind

from .build_check import BuildCheck
from .licensing import LICENSE_MEMBER, SPDX
from .model_description import CAUSALITY, VERSION
from .platforms import PLATFORMS, binary_folder

SOURCES = (
    "Marin, <i>Rigid Body Motion</i> (Analytical Dynamics, lecture 7); the lecture notes "
    "<i>Kinematics of rigid-body rotation</i>; MIT 2.003J <i>Rigid Body Dynamics</i> and its notation handout. "
    "Section numbers (§) refer to docs/theory.md of rbfmu, which maps each equation to the function implementing it."
)

# The rigid body's own equations, every scene's; each feature's come from its unit
# (modelsrc.registry.feature_docs: the descriptors the model is built from, FeatureDoc).
KINEMATICS = (
    ("R(q) = (w² − v·v) 1 + 2 v vᵀ + 2 w [v]×,  q = (w, v) unit, body → world", "§1.1 (Marin p. 1)"),
    ("q̇ = ½ q ⊗ (0, ω),  ω in the body frame; q projected to |q| = 1 after each step", "§1.2 (Marin p. 2)"),
)
EULER = ("I ω̇ + ω × (I ω) = τ  (body frame, full inertia tensor about the rotation point)", "§2.1 (Marin; MIT 2.003J)")


def frame_of(name: str, description: str) -> str:
    """The frame a variable is expressed in, from its name and description."""
    base = name.removeprefix("der(")
    if base.startswith("q["):
        return "body → world"
    if base.startswith("euler_zxz"):
        return "body → world (z-x-z)"
    if base.startswith(("q_lvlh", "rpy_lvlh")):
        return "body → LVLH"
    if "body axis" in description or base.startswith(("w_body", "tau_body", "L_body", "r_cm", "I")):
        return "body"
    if "world axis" in description or base.startswith(("w_world", "tau_world", "L_world", "g[", "sensor")):
        return "world"
    return ""


def _table(head: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    assert all(head), f"every column needs a heading, got {head!r}"
    cells = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{cells}</tr>{body}</table>"


def _vec(x: np.ndarray) -> str:
    return html.escape(np.array2string(np.asarray(x, dtype=float), precision=6, separator=", "))


def _body(model: RigidBodyModel) -> str:
    sc = model.scene
    docs = feature_docs(sc)
    feats = "; ".join(f"{name}: {d.summary}" for name, d in docs) or "none: a free rigid body, no torque"
    rows = [
        ("features", html.escape(feats)),
        ("inertia about the centre of mass (kg·m², body)", _vec(sc.inertia)),
        ("start angular velocity ω0 (rad/s, body)", _vec(sc.w0)),
        ("start orientation q0 (body → world, scalar first)", _vec(sc.q0)),
    ]
    if sc.has("gravity"):
        rows += [("mass (kg)", f"{sc.mass:g}"), ("pivot → centre of mass r_cm (m, body)", _vec(sc.r_cm))]
        rows += [("gravity g (m/s², world)", _vec(sc.g))]
    if sc.has("friction"):
        rows.append(("viscous friction c (N·m·s/rad)", f"{sc.c_friction:g}"))
    if sc.has("orbit"):
        rows.append(("circular orbit rate n (rad/s)", f"{sc.orbit_rate:g}"))
    if sc.has("central_gravity"):
        rows.append(("central body at the origin, G M = μ (m³/s²)", f"{sc.mu:g}"))
    for name, r in sc.rotors.items():  # the inertia above is the whole body's, rotors included (§8)
        if r.speed:  # Ω is an input (§8.5); a propeller's thrust and drag (§8.6)
            prop = (
                f", at {_vec(r.position)} m, k_f {r.k_f:g} N·s², k_m {r.k_m:g} N·m·s²" if r.position is not None else ""
            )
            rows.append(
                (f"rotor {html.escape(name)} (speed mode): axis g (body), J (kg·m²)", f"{_vec(r.axis)}, {r.J:g}{prop}")
            )
            continue
        lag = f" (command mode, τ_m {r.settings['tau_m']:g} s)" if r.mode == "command" else ""  # §8.8
        rows.append(
            (
                f"rotor {html.escape(name)}{lag}: axis g (body), J (kg·m²), start Ω0 (rad/s, relative)",
                f"{_vec(r.axis)}, {r.J:g}, {r.Omega0:g}",
            )
        )
    return _table(("property", "value"), rows)


def _equations(model: RigidBodyModel) -> str:
    docs = feature_docs(model.scene)
    eqs = list(KINEMATICS)
    if any(d.replaces_euler for _, d in docs):  # the gyrostat's, a held rate: in place of §2.1
        eqs.append((EULER[0], f"{EULER[1]}: the rigid body's, replaced here by the equations of the features below"))
    else:
        eqs.append(EULER)
    for _, d in docs:
        eqs.extend(d.equations)
    rows = [(f"<code>{html.escape(eq)}</code>", html.escape(src)) for eq, src in eqs]
    return _table(("equation", "source"), rows) + f"<p class='small'>{SOURCES}</p>"


def _conserved(model: RigidBodyModel) -> str:
    kept = conserved_quantities(model.scene)
    if not kept:
        return "<p>None: forces or torques work on the body (inputs, friction, a moving pivot).</p>"
    items = "".join(f"<li>{html.escape(k)}</li>" for k in kept)
    inputs = model.scene.input_names
    held = (
        f" With the inputs ({html.escape(', '.join(inputs))}) at the scene's values; an input the importer "
        "sets otherwise may work on the body."
        if inputs
        else ""
    )
    return f"<ul>{items}</ul><p class='small'>From the features the model is built from (modelsrc.registry).{held}</p>"


def _variables(model: RigidBodyModel) -> str:
    rows = []
    for vr, v in enumerate(model.variables):
        causality, variability, _ = CAUSALITY[v.kind]
        start = (
            ""
            if v.start is None or v.kind in (Kind.INDEPENDENT, Kind.OUTPUT, Kind.DERIVATIVE, Kind.LOCAL)
            else f"{v.start:.10g}"
        )
        rows.append(
            (vr, f"<code>{html.escape(v.name)}</code>", causality, variability, start, html.escape(v.unit or ""),
             html.escape(frame_of(v.name, v.description)), html.escape(v.description))
        )  # fmt: skip
    values = ", ".join(f"{METHODS[m].value} = {m}" for m in model.methods)
    rows.append((len(model.variables), "<code>method</code>", "parameter", "tunable",
                 str(METHODS[model.default_method].value), "", "", f"integrator (enumeration): {values}"))  # fmt: skip
    return _table(("vr", "name", "causality", "variability", "start", "unit", "frame", "description"), rows)


def _methods(model: RigidBodyModel) -> str:
    rows = []
    for name in model.methods:
        m = METHODS[name]
        label = f"<code>{name}</code>" + (" (default)" if name == model.default_method else "")
        rows.append((m.value, label, m.order, html.escape(m.kind), html.escape(m.preserves),
                     html.escape(m.needs or "-"), html.escape(m.use_for)))  # fmt: skip
    advice = (
        "Choose by what the run needs: <code>rk4</code> for general use (cheapest step); <code>rk8</code> for "
        "tight tolerances; the Gauss-Legendre methods keep |L| and E exactly over long runs; "
        "<code>splitting</code> and <code>exact_free</code> (principal bodies) stay exact at fast spin and stiff "
        "friction. Accuracy is set by <code>tolerance</code> (relative error per second of simulated time, "
        f"default {DEFAULT_TOLERANCE:g}): the methods with an error estimate (rk4, rk8, the Gauss-Legendre "
        "methods) choose their internal steps to keep it, ending on every communication point; "
        "<code>h_max</code> caps those steps (0: no cap). With <code>tolerance</code> = 0 (and for the "
        "splittings always) the steps are fixed: "
        "ceil(H/h_max) per communication step, refined automatically for fast spin and stiffness "
        "(docs/theory.md §5.4, §5.5). The variables <code>internal_steps</code>, <code>rejected_steps</code>, "
        "<code>h_last</code>, <code>h_next</code> and <code>tolerance_effective</code> (the tolerance held: more than "
        "<code>tolerance</code> where the error estimate cannot resolve it) report what the last doStep did. An "
        "importer's tolerance (EnterInitializationMode, SetupExperiment) sets <code>tolerance</code> in "
        "Co-Simulation unless the parameter was set."
    )
    head = ("value", "name", "order", "kind", "keeps exactly", "needs", "use it for")
    return _table(head, rows) + f"<p>{advice}</p>"


def _fmt(x: float | None, none: str = "not conserved here (or not an output)") -> str:
    """A measured figure: "0 exactly" for an exact 0 (a bound compared with it says nothing), `none` for None."""
    if x is None:
        return none
    return "0 exactly (no rounding either)" if x == 0.0 else f"{x:.2e}"


def _validation(check: BuildCheck | None, scene_orbit: bool = False) -> str:
    if check is None or check.error:
        why = "instrumented build (extra compiler flags)" if check is None else check.error.strip().rstrip(".")
        return f"<p>Not measured for this build: {html.escape(why)}.</p>"
    rel = check.w_diff / check.w_scale if check.w_scale > 0 else float("nan")
    w_row = (
        "0 exactly: both runs agree to the last bit (a motion both integrate exactly; no error estimate)"
        if check.w_diff == 0.0
        else f"{check.w_diff:.2e} rad/s (relative to max ‖ω‖∞ = {check.w_scale:.4g} rad/s: {rel:.2e})"
    )
    energy = "not conserved: in an orbit E_jacobi is (Conserved quantities)" if scene_orbit else None
    rows = [
        ("experiment", f"0 … {check.stop_time:g} s, communication step {check.step:g} s, default start values"),
        (f"{check.method} ({check.settings}) vs {check.reference} ({check.ref_settings}): ‖ω(T) − ω_ref(T)‖∞",
         w_row),
        ("same, ‖q(T) − q_ref(T)‖∞", _fmt(check.q_diff)),
        ("max ||q| − 1|", _fmt(check.qnorm)),
        ("max relative drift of E", _fmt(check.E_drift, energy) if energy else _fmt(check.E_drift)),
        ("max relative drift of |L_world|", _fmt(check.L_drift)),
        ("wall time of both runs (this build machine, via fmpy)", f"{check.wall_s:.2f} s"),
    ]  # fmt: skip
    note = (
        "Measured when this FMU was built, on its own binary for the build machine "
        "(fmu/build/build_check.py): the first row estimates the error of the default settings "
        "when the reference is far more accurate."
    )
    return _table(("quantity", "value"), rows) + f"<p class='small'>{note}</p>"


SOURCE_BUILD = (
    "Without CMake, any C compiler builds the same binary from <code>sources/*.c</code> (e.g. "
    "<code>cc -shared -fPIC -O2 sources/*.c -lm</code>): the sources hide every symbol but the "
    "fmi3*/fmi2* functions and turn floating-point contraction off themselves "
    "(<code>rbfmu_build.h</code>); only value-changing options (<code>-ffast-math</code>) are refused."
)


def oldest_system(platform: str) -> str:
    """The oldest C library / OS the zig-built binary of `platform` loads on, from its zig
    target (fmu.build.platforms.PLATFORMS): "glibc 2.17", "macOS 11.0", or "Windows" (x86_64)."""
    target = PLATFORMS[platform].zig_target
    _, _, version = target.partition(".")
    if "-linux-gnu" in target:
        return f"glibc {version}"
    return f"macOS {version}" if "-macos" in target else "Windows"


def _platforms(platforms: Sequence[str], host: str, fmi_version: str) -> str:
    portable = len(platforms) > 1 and host in PLATFORMS  # fmu.build.build_fmu: zig builds every binary then
    rows = [
        (f"<code>binaries/{binary_folder(p, fmi_version)}</code>",
         ("zig cc" if portable else "gcc on the build machine")
         + ("; run at build time (validation above)" if p == host else "; not run at build time"),
         f"{oldest_system(p)} or newer" if portable or p != host
         else "the build machine's glibc or newer (a host-only build: <code>--platforms all</code> "
              "builds it for glibc 2.17)")
        for p in platforms
    ]  # fmt: skip
    rebuild = (
        "Another platform: rebuild from <code>sources/</code> with CMake: <code>cmake -S sources -B build &amp;&amp; "
        "cmake --build build --config Release &amp;&amp; cmake --install build --config Release</code> installs "
        "<code>binaries/&lt;platform&gt;/</code> into the unpacked FMU."
    )
    return _table(("binary", "built with", "loads on"), rows) + f"<p>{rebuild} {SOURCE_BUILD}</p>"


def index_html(
    model: RigidBodyModel, fmi_version: str, platforms: Sequence[str], host: str, check: BuildCheck | None
) -> str:
    """The text of documentation/index.html."""
    sc = model.scene
    icon = "../terminalsAndIcons/icon.png" if fmi_version == "3" else "../model.png"
    licence = LICENSE_MEMBER[fmi_version].removeprefix("documentation/")
    style = (
        "body{font-family:sans-serif;max-width:62em;margin:2em auto;line-height:1.4}"
        "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em;"
        "text-align:left;vertical-align:top}.small{font-size:.9em;color:#444}img{float:right}"
    )
    parts = [
        "<!DOCTYPE html>",
        f"<html lang='en'><head><meta charset='utf-8'><title>{html.escape(sc.name)}</title>",
        f"<style>{style}</style></head><body>",
        f"<img src='{icon}' width='160' height='160' alt='the body'>",
        f"<h1>{html.escape(sc.name)}</h1><p>{html.escape(sc.description)}</p>",
        f"<p class='small'>FMI {fmi_version}.0, Co-Simulation and Model Exchange; generated by rbfmu {VERSION}. "
        "SI units; frames: <b>body</b> (rotating with the body) and <b>world</b> (inertial). "
        f"Licence: {SPDX} (<a href='{licence}'>{licence}</a>).</p>",
        "<h2>The body</h2>",
        _body(model),
        "<h2>Equations</h2>",
        _equations(model),
        "<h2>Conserved quantities</h2>",
        _conserved(model),
        "<h2>Variables</h2>",
        _variables(model),
        "<h2>Integrators (<code>method</code>)</h2>",
        _methods(model),
        "<h2>Validation measured for this scene</h2>",
        _validation(check, sc.has("orbit")),
        "<h2>Platforms</h2>",
        _platforms(platforms, host, fmi_version),
        "</body></html>",
        "",
    ]
    return "\n".join(parts)
