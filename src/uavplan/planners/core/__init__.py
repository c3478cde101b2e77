"""The planner contract every family builds on: options (:mod:`.options`), a run's budget,
termination and tracking (:mod:`.run`), results and the plan's story (:mod:`.results`,
:mod:`.events`), the registry (:mod:`.registry`) and :class:`~.base.Planner` itself, with the
flight a plan declares (:mod:`.flight`: what the result guarantees is the flight it states, so
the contract defines it). It imports no planner family and no policy: the polish a single
UAV's path may get (:mod:`uavplan.planners.polish`) is handed to :meth:`~.base.Planner.plan` by
the layers that choose it."""
