"""The independent plan verifier (see :mod:`uavplan.verify.core`)."""
