"""Tolerances, in one place (metres and seconds unless stated).

Planning checks use :data:`BAND_TOL` and :data:`BOUNDS_TOL`; the independent verifier its own,
looser :data:`VERIFY_TOL` (it reads plans rounded to 6 decimals). Numerical guards that belong to
one algorithm's arithmetic stay named beside it: Dubins round-off allowances
(``uavplan.smoothing.dubins._EPS``, ``_MAX_SNAP``, ``_SAME_CIRCLE``), the visibility graph's
offsets (``uavplan.world.visibility.OFFSET_REL``, ``ANGLE_TOL``), RSCDWOA's ``CHAOS_EPS``.
"""

#: A waypoint may leave the altitude band by this much (round-off of height arithmetic).
BAND_TOL = 1e-9
#: A point may leave the scenario's box by this much.
BOUNDS_TOL = 1e-9
#: A 2-D segment is rejected without the exact test when a separating axis keeps it apart from
#: a convex polygon (or a polygon's convex hull) by more than this fraction of the coordinates'
#: magnitude: far above rounding, so the exact test would find such a pair apart too (it never
#: rejects a touching segment).
SAT_TOL_REL = 1e-9
#: Duplicate waypoints closer than this are one (Dubins smoothing, fleet pose times).
DUPLICATE_TOL = 1e-9
#: RRT*: a rewire must shorten the cost-to-come by more than this (no churn on round-off).
REWIRE_TOL = 1e-9
#: Planning's relative slack on the speed limits (round-off of times computed from lengths).
SPEED_RTOL = 1e-9
#: Planning's length slack per segment on the speed limits, metres.
SPEED_SLACK = 1e-9
#: A reserved flight (densely sampled curves) is kept as fewer segments that stay within this
#: many metres of it, padded by their deviation (planning checks stay conservative).
RESERVE_TOL = 0.1
#: Distances and clearances the verifier accepts below the required value.
VERIFY_TOL = 1e-6
#: The verifier's relative slack on the speed limits (a fraction, where planning's is
#: :data:`SPEED_RTOL`: the verifier reads times and points rounded to a plan file's decimals).
VERIFY_SPEED_RTOL = 1e-6
#: The verifier's length slack per segment for plan files' 6-decimal rounding: this many metres
#: per (speed + 2) m/s of speed.
VERIFY_ROUNDING = 1e-6
#: A turn-radius estimate from a trajectory's samples may fall this fraction below the required
#: radius: samples of an arc of radius R at spacing h <= R / 4 estimate its curvature within that
#: (the estimate theta / mean chord exceeds 1 / R by the factor (phi / 2) / sin(phi / 2)).
TURN_RTOL = 0.01
#: Degrees: a trajectory whose heading changes by more than this at one point cannot be checked
#: for turn radius from its samples, and fails the turn check when a turn radius is declared.
MAX_SAMPLE_TURN_DEG = 30.0
#: Degrees of slack on the climb and descent angle limits (coordinates rounded to 6 decimals).
ANGLE_TOL_DEG = 1e-4
#: Metres: a fixed wing's height flown in the wind that stays within this of its plan is not
#: checked again (the calibrated tracking error was measured on flights that carry such gaps;
#: :func:`uavplan.world.execution.height_lag`).
LAG_TOL = 0.5
