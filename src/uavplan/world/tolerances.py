"""Tolerances, in one place (metres and seconds unless stated).

Planning checks use :data:`BAND_TOL`; the independent verifier its own, looser
:data:`VERIFY_TOL` (it reads plans rounded to 6 decimals).
"""

#: A waypoint may leave the altitude band by this much (round-off of height arithmetic).
BAND_TOL = 1e-9
#: Duplicate waypoints closer than this are one (Dubins smoothing, fleet pose times).
DUPLICATE_TOL = 1e-9
#: RRT*: a rewire must shorten the cost-to-come by more than this (no churn on round-off).
REWIRE_TOL = 1e-9
#: Distances and clearances the verifier accepts below the required value.
VERIFY_TOL = 1e-6
#: The verifier's relative slack on the speed limit.
VERIFY_SPEED_RTOL = 1e-6
