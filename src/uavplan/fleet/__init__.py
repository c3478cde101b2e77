"""Fleet-level tools (many UAVs at once). Submodules are imported on demand (for example
:mod:`uavplan.fleet.verify`, the independent plan verifier); nothing heavy is imported here."""
