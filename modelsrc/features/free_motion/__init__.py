"""The moving reference point: scene_file.py reads its part of a scene, feature.py its equations and descriptor."""
