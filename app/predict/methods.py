"""The names of the prediction methods (paper Table I rows); no heavy imports, the CLI reads it at start."""
from __future__ import annotations

QUERY_FEATURE = tuple(f"{q}-{f}" for q in ("bps", "ibs") for f in ("ndf", "scf", "nif"))
TEMPLATE_METHODS = ("nift", *QUERY_FEATURE)  # imitate templates (Eq. 5); nift = ibs-nif
METHODS = (*TEMPLATE_METHODS, "cpd")


def check_method(method: str) -> str:
    """The canonical name of a method ('nift' -> 'ibs-nif'), or a one-line error."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    return "ibs-nif" if method == "nift" else method
ORACLE = "teacher"  # the scripted teacher's poses from the simulator's ground truth (an upper bound)
SIM_METHODS = (*METHODS, ORACLE)  # what the simulated jobs and benchmark accept
