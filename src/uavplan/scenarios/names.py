"""The names of the RGG-PSO+ scene family (:mod:`uavplan.scenarios.generators` builds the
scenes): kept apart, without imports, so that listing the experiment plans does not load the
world model."""

from __future__ import annotations

from collections.abc import Iterable

#: The ten obstacle counts of the family (the paper's "5-15", 15 exclusive).
SETTINGS: tuple[int, ...] = tuple(range(5, 15))
#: Scenes per obstacle count.
PER_SETTING = 100


def rgg_name(n_obstacles: int, index: int) -> str:
    """``rgg-n07-i042`` style name of scene ``index`` with ``n_obstacles`` obstacles."""
    return f"rgg-n{n_obstacles:02d}-i{index:03d}"


def family_names(per_setting: int = PER_SETTING, settings: Iterable[int] = SETTINGS) -> list[str]:
    """Names of the family's scenes, in :func:`uavplan.scenarios.generators.rgg_family` order."""
    return [rgg_name(n, i) for n in settings for i in range(per_setting)]
