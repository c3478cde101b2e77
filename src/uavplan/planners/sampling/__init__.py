"""Sampling-based planners: RRT* (PPSwarm Alg. 1) and its grid index and kernels; the random
geometric graph (``rgg``) and RGG-PSO / RGG-PSO+ (Liu et al. 2024), whose particles start from
the graph's paths. Every module is imported, so that its planners register."""

from uavplan._discovery import import_submodules

MODULES = import_submodules(__name__, __path__)
