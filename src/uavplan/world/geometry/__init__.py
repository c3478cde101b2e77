"""Exact, batched geometry kernels: segments against circles, cylinders and polygons, one
module per kind of shape (``cylinders``, ``circles``, ``polygons``, ``moving``) and the 2-D
scene pass over circles and polygons together (``scene2d``); every name is also here.

Every kernel takes polylines as ``(pop, n_points, dim)`` arrays and returns one value per
``(path, segment, obstacle)``, or per path where a cost or check only needs their sum or least
(the fused ``*_batch`` kernels, which never build the (P, N - 1, J) array); the hot ones are
Numba-parallel over the population, and each has a plain NumPy or Python reference
(``*_reference``, or the per-pair kernel) that the tests compare against.
"""

from __future__ import annotations

from uavplan.world.geometry._grid import BLOCK, GRID_MIN_OBSTACLES
from uavplan.world.geometry.circles import (
    circle_grid,
    circle_inside_grid,
    circle_inside_length,
    segment_circle_inside_fraction,
)
from uavplan.world.geometry.cylinders import (
    FUSED_MATH,
    GRID_MIN_CYLINDERS,
    as_3d,
    clipped_dist,
    cylinder_distances,
    cylinder_grid,
    cylinder_grid_pass,
    cylinder_hits,
    cylinder_overlap,
    cylinder_overlap_batch,
    cylinder_threat,
    cylinder_threat_batch,
    gridded,
    point_segment_distance_2d,
    seg_cyl_dist,
    seg_setup,
    segment_cylinder_distance,
    segment_cylinder_distance_reference,
    soa,
)
from uavplan.world.geometry.moving import timed_path_min_distance
from uavplan.world.geometry.polygons import (
    convex_hulls,
    pack_polygons,
    point_in_polygon,
    polygon_convexity,
    segment_polygon_distance,
    segment_polygon_inside_fraction,
    track_crosses_itself,
)
from uavplan.world.geometry.scene2d import (
    hull_edges,
    scene2d_batch,
    scene2d_grid_kernel,
    scene2d_kernel,
    scene_prep,
)
from uavplan.world.obstacle_index import GRID_MAX_CELLS, by_content

__all__ = [
    "BLOCK",
    "FUSED_MATH",
    "GRID_MAX_CELLS",
    "GRID_MIN_CYLINDERS",
    "GRID_MIN_OBSTACLES",
    "as_3d",
    "by_content",
    "circle_grid",
    "circle_inside_grid",
    "circle_inside_length",
    "clipped_dist",
    "convex_hulls",
    "cylinder_distances",
    "cylinder_grid",
    "cylinder_grid_pass",
    "cylinder_hits",
    "cylinder_overlap",
    "cylinder_overlap_batch",
    "cylinder_threat",
    "cylinder_threat_batch",
    "gridded",
    "hull_edges",
    "pack_polygons",
    "point_in_polygon",
    "point_segment_distance_2d",
    "polygon_convexity",
    "scene2d_batch",
    "scene2d_grid_kernel",
    "scene2d_kernel",
    "scene_prep",
    "seg_cyl_dist",
    "seg_setup",
    "segment_circle_inside_fraction",
    "segment_cylinder_distance",
    "segment_cylinder_distance_reference",
    "segment_polygon_distance",
    "segment_polygon_inside_fraction",
    "soa",
    "timed_path_min_distance",
    "track_crosses_itself",
]
