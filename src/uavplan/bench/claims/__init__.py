"""The claims ledger: every headline claim of the four papers judged from the stored runs
(:mod:`uavplan.bench.claims.base`). Each module here registers one paper's claims and every
module is imported, so a new paper's claims are a new module."""

from uavplan._discovery import import_submodules
from uavplan.bench.claims.base import CLAIMS, VERDICTS, Claim, Finding, build_ledger

MODULES = import_submodules(__name__, __path__)

__all__ = ["CLAIMS", "VERDICTS", "Claim", "Finding", "build_ledger"]
