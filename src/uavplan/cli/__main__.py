"""``python -m uavplan.cli``."""

from uavplan.cli import main

main()
