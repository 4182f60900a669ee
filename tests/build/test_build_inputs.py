"""What a scene file puts into a build is checked: its name, its description, and the token pairing binary and XML.

A description becomes an XML attribute of modelDescription.xml (both FMI versions): every
character XML 1.0 allows must come back unchanged, and one it does not allow is refused
when the scene is read. The name becomes the modelIdentifier (file names, C symbols). The
instantiation token must differ between any two builds whose binaries or variables
differ, the default method included, so that a modelDescription and a binary of
different builds are never accepted as a pair.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from fmu.build.build_fmu import build_fmu
from fmu.build.model_description import fmi2_model_description, fmi3_model_description
from modelsrc.errors import ModelInputError
from modelsrc.model import build_model
from modelsrc.scene import MAX_NAME_LENGTH, load_scene

from ..harness.fmi3_ctypes import Fmi3Library, extract_fmu

BODY = (
    "[body]\nprincipal_moments = [1.0, 2.0, 3.0]\n[initial]\nw_body = [0.0, 0.0, 1.0]\n"
    '[experiment]\nmethods = ["rk4", "rk8"]\n'
)


def _scene(tmp_path, head: str, extra: str = "", file: str = "body.toml"):
    path = tmp_path / file
    path.write_text(head + "\n" + BODY + extra)
    return path


def test_description_with_xml_special_characters_round_trips(tmp_path):
    # a TOML basic string: tab, newline, carriage return, markup characters, quotes, non-ASCII,
    # a character outside the BMP
    text = "tab\there\nnew line\r, <tag> & \"quotes\" 'apostrophes', ünïcödé é 漢字 \U0001f680 ]]> --"
    escaped = "".join(f"\\u{ord(c):04x}" if ord(c) < 0x20 or c in '"\\' else c for c in text)  # TOML escapes
    toml = f'name = "body"\ndescription = "{escaped}"'
    model = build_model(load_scene(_scene(tmp_path, toml)))
    for describe in (fmi3_model_description, fmi2_model_description):
        root = ET.fromstring(describe(model, "{token}"))  # well-formed, or this raises
        assert root.get("description") == text


@pytest.mark.parametrize("char", ["\\u0001", "\\u0008", "\\u000b", "\\u001f", "\\ufffe", "\\uffff"])
def test_description_with_a_character_xml_forbids_is_refused(tmp_path, char):
    path = _scene(tmp_path, f'name = "body"\ndescription = "ok so far {char} then"')
    with pytest.raises(ModelInputError, match=rf"'description': character 10 is U\+{char[2:].upper()}, which XML 1.0"):
        load_scene(path)


def test_description_must_be_a_string(tmp_path):
    with pytest.raises(ModelInputError, match="'description': must be a string, got"):
        load_scene(_scene(tmp_path, 'name = "body"\ndescription = [1, 2]'))


@pytest.mark.parametrize(
    "name, match",
    [
        ("b" * (MAX_NAME_LENGTH + 1), f"has {MAX_NAME_LENGTH + 1} characters, at most {MAX_NAME_LENGTH} are allowed"),
        ("x" * 300, "has 300 characters"),
        ("bödy", "must be an ASCII identifier"),
        ("9lives", "must be an ASCII identifier"),
    ],
)
def test_name_must_be_a_short_ascii_identifier(tmp_path, name, match):
    with pytest.raises(ModelInputError, match=match):
        load_scene(_scene(tmp_path, f'name = "{name}"'))
    assert load_scene(_scene(tmp_path, f'name = "{"b" * MAX_NAME_LENGTH}"')).name == "b" * MAX_NAME_LENGTH


@pytest.mark.parametrize(
    "content, match",
    [
        ("w_body = " + "[" * 5000 + "]" * 5000, "nested too deeply"),
        (b'name = "b\xff"', "not UTF-8 text"),
    ],
    ids=["nested", "not_utf8"],
)
def test_unreadable_scene_files_are_one_error(tmp_path, content, match):
    path = tmp_path / "bad.toml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(ModelInputError, match=f"scene file {path}: .*{match}"):
        load_scene(path)


@pytest.mark.slow
def test_token_changes_with_the_default_method_and_a_mixed_pair_is_refused(tmp_path):
    """Two builds of the same scene that differ only in the default method: different
    instantiation tokens; the binary of one with the modelDescription of the other returns
    NULL from instantiation, naming both tokens."""
    fmus = {}
    for method in ("rk4", "rk8"):
        (tmp_path / method).mkdir()
        path = _scene(tmp_path / method, 'name = "body"', f'method = "{method}"\n')
        fmus[method] = extract_fmu(build_fmu(load_scene(path), tmp_path / method / "out"), tmp_path / method / "fmu")
    lib = {m: Fmi3Library(d) for m, d in fmus.items()}
    assert lib["rk4"].info.token != lib["rk8"].info.token
    assert lib["rk4"].info.int64_start["method"] != lib["rk8"].info.int64_start["method"]
    so_rk8 = fmus["rk8"] / "binaries" / "x86_64-linux" / "body.so"
    mixed = Fmi3Library(fmus["rk4"], so_path=so_rk8)  # rk4's modelDescription, rk8's binary
    inst = mixed.instantiate()
    assert not inst.handle
    text = "\n".join(inst.errors_since(0))
    assert f"'{lib['rk4'].info.token}' does not match this FMU's '{lib['rk8'].info.token}'" in text
    own = lib["rk8"].instantiate()  # each binary with its own modelDescription works
    assert own.handle
    own.free()
