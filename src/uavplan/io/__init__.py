"""Reading and writing uavplan files (scenario files: :mod:`uavplan.io.scenario_file`)."""
