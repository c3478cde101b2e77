"""Closed-loop flight simulation of exported missions: each UAV flies the MAVLink items
``uavplan export`` writes (thinned waypoints, speed commands, its take-off time) with an
autopilot's guidance law through a point-mass airframe model, in a steady wind with Dryden
turbulence and a drifting position estimate, the whole fleet at once in one Numba kernel.

* :mod:`uavplan.world.airframes`: UAV classes (fixed wing, multirotor) and their airframes: the
  dynamics' time constants and limits, the guidance gains, the navigation error.
* :mod:`uavplan.sim.turbulence`: the Dryden gust model of MIL-HDBK-1797 (low altitude).
* :mod:`uavplan.sim.missions`: an exported mission read back into local legs.
* :mod:`uavplan.sim.fleet`: the batched model (L1 lateral guidance, a total-energy-style
  height and speed loop for fixed wings; a position and velocity tracker for multirotors).
* :mod:`uavplan.sim.runs`: one simulated execution of a plan: the sampled conditions, the
  flown tracks, their tracking and timing errors. The independent verifier checks the tracks
  (:mod:`uavplan.bench.simulation`, ``uavplan simulate``); this package does not import it.
* :mod:`uavplan.sim.reference`: the same guidance flown through maintained flight-dynamics
  libraries (JSBSim, rotorpy; the optional extra ``uavplan[sim]``), what the batched model is
  validated against.
"""
