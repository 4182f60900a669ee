"""Numpy helpers the references and checks share: rotations and fits of sampled trajectories.

``rotation_np`` (quaternions, matrices, z-x-z Euler angles) and ``motion_fits`` (growth
rates, periods, extrema, crossings of a sampled trajectory). No physics of any scene.
"""
