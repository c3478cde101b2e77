"""Scenario files: a :class:`~uavplan.world.Scenario` written as YAML or JSON.

The file format is a pydantic (v2) schema, :class:`ScenarioSpec`; the full reference, with units,
defaults and an example, is ``docs/scenario-format.md``. Frame: x east, y north, z up, metres.

* :func:`load_scenario` reads a ``.yaml``/``.yml``/``.json`` file (YAML for any other suffix) and
  builds the :class:`~uavplan.world.Scenario`; :func:`scenario_from_dict` does the same for an
  already parsed mapping.
* :func:`scenario_to_dict` / :func:`save_scenario` write the validated file-level spec back (the
  loaded Scenario keeps it in ``metadata["spec"]``), atomically.
* :func:`schema` is the JSON Schema of the format.
* ``fleet:`` (instead of ``tasks:``) generates the tasks with
  :func:`uavplan.world.fleet_tasks.fleet_tasks`; the spec kept and written back holds the
  ``fleet`` block, which regenerates the same tasks.

Every problem with a file is reported at once by :class:`ScenarioFileError`, one line per problem:
``<file>: <field path> = <value>: <reason>``, e.g.
``bad.yaml: tasks[0].start = [5000, 10, 150]: outside the bounds [1.0, 1.0, 48.0]..[...]``.
"""

from uavplan.io.scenario_file.errors import ScenarioFileError
from uavplan.io.scenario_file.read import (
    load_scenario,
    parse_scenario_spec,
    read_scenario_data,
    scenario_from_dict,
)
from uavplan.io.scenario_file.schema import ScenarioSpec, schema
from uavplan.io.scenario_file.write import save_scenario, scenario_to_dict, spec_from_scenario

__all__ = [
    "ScenarioFileError",
    "ScenarioSpec",
    "load_scenario",
    "parse_scenario_spec",
    "read_scenario_data",
    "save_scenario",
    "scenario_from_dict",
    "scenario_to_dict",
    "schema",
    "spec_from_scenario",
]
