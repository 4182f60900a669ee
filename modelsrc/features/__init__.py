"""The capabilities a scene may use, one unit each: a module, or a folder whose feature.py holds its descriptor.

Each unit defines ``FEATURE`` (a ``modelsrc.feature.Feature``): its part of the scene
file, its flags, builders and contributions. ``modelsrc.registry`` finds the units; no
unit imports another (tests/test_structure.py): what two features share goes through the
body's record (``modelsrc.assembly.Assembly``) and its sums (docs/features.md).
"""
