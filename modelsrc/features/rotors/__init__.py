"""The rotors (the gyrostat): scene_file.py reads their tables, feature.py holds their equations and descriptor."""
