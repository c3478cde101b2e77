"""``wpl``: the MAVLink plain-text mission ``QGC WPL 110``, one file per UAV, as Mission Planner,
QGroundControl and MAVProxy load it (pymavlink's ``mavwp.MAVWPLoader`` reads it back in the
tests). A header line, then one row per item with 12 tab-separated columns: ``seq``,
``current``, ``frame``, ``command``, ``param1``-``param4``, ``x`` (latitude), ``y``
(longitude), ``z`` (altitude in the row's frame), ``autocontinue``. Row 0 is the home position
(AMSL, the ground under the start). Latitude and longitude carry 8 decimals (about 1 mm)."""

from __future__ import annotations

import math
from pathlib import Path

from uavplan.io.atomic import write_texts_atomic
from uavplan.io.missions import Mission, register_exporter, uav_file


def _num(v: float, decimals: int) -> str:
    return "0" if math.isnan(v) else f"{v:.{decimals}f}"


def wpl_text(mission: Mission, k: int) -> str:
    """UAV ``k``'s mission as ``QGC WPL 110`` text."""
    tr = mission.trajectories()[k]
    home = mission.home(tr)
    rows = [f"0\t1\t0\t16\t0\t0\t0\t0\t{home[0]:.8f}\t{home[1]:.8f}\t{home[2]:.3f}\t1"]
    for seq, it in enumerate(mission.items(tr), start=1):
        p = it.params
        head = "\t".join(_num(v, 6) for v in p[:4])
        rows.append(f"{seq}\t0\t{it.frame}\t{it.command}\t{head}\t{_num(p[4], 8)}\t"
                    f"{_num(p[5], 8)}\t{_num(p[6], 3)}\t1")  # fmt: skip
    return "QGC WPL 110\n" + "\n".join(rows) + "\n"


@register_exporter("wpl", ".waypoints", "MAVLink QGC WPL 110 text mission", per_uav=True)
def write_wpl(mission: Mission, out: Path) -> list[Path]:
    files = [(uav_file(out, tr.id, ".waypoints"), wpl_text(mission, k))
             for k, tr in enumerate(mission.trajectories())]  # fmt: skip
    return write_texts_atomic(files)
