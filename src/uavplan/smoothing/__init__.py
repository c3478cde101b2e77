"""Path smoothing: Dubins CSC curves (PPSwarm Sect. 4.4)."""

from uavplan.smoothing.dubins import (
    CSC_KINDS,
    DubinsPath,
    SmoothedPath,
    discrete_curvature,
    dubins_csc,
    max_discrete_curvature,
    midpoint_poses,
    sample_pieces,
    schedule,
    smooth_path,
    waypoint_headings,
    wrap_angle,
)

__all__ = [
    "CSC_KINDS",
    "DubinsPath",
    "SmoothedPath",
    "discrete_curvature",
    "dubins_csc",
    "max_discrete_curvature",
    "midpoint_poses",
    "sample_pieces",
    "schedule",
    "smooth_path",
    "waypoint_headings",
    "wrap_angle",
]
