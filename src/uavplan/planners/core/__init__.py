"""The planner contract every family builds on: options (:mod:`.options`), a run's budget,
termination and tracking (:mod:`.run`), results and the plan's story (:mod:`.results`,
:mod:`.events`), the registry (:mod:`.registry`) and :class:`~.base.Planner` itself, with the
flight a plan declares (:mod:`.flight`) and the polish a single UAV's path may get
(:mod:`.polish`). It imports no planner family."""
