"""The prediction methods (paper Table I rows, and the oracle): one record each, the only place that
knows a method by its name. No heavy imports: the CLI reads it at start.

Every branch on a method goes through its record (`method(name).template`, `.true_poses`, `.family`);
`tests/test_method_registry.py` fails on a comparison of a method's name to a string literal
anywhere else.
"""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


class Family(Enum):
    """How a method's predictor is built."""

    TEMPLATE = "template"  # imitate the demos' NIT templates (Eq. 5): `app.predict.predict`
    REGISTRATION = "registration"  # register the demos' clouds to the target (CPD): `app.predict.predict`
    ORACLE = "oracle"  # the simulator's true poses, an upper bound: `app.simcell.oracle`, simulation only


@dataclass(frozen=True)
class Method:
    """One method: its name, the names it also answers to, its family, and a template method's parts."""

    name: str
    family: Family
    aliases: tuple[str, ...] = ()
    query: str | None = None  # template methods: the query points (ibs, bps)
    feature: str | None = None  # template methods: the feature field (nif, scf, ndf)

    @property
    def template(self) -> bool:
        """Whether it imitates templates (and so can imitate a place again, look for a hole, ...)."""
        return self.family is Family.TEMPLATE

    @property
    def true_poses(self) -> bool:
        """Whether it reads the simulator's ground truth instead of the cloud (the oracle)."""
        return self.family is Family.ORACLE

    @property
    def names(self) -> tuple[str, ...]:
        return (self.name, *self.aliases)


def _template(query: str, feature: str, aliases: tuple[str, ...] = ()) -> Method:
    return Method(f"{query}-{feature}", Family.TEMPLATE, aliases, query, feature)


ORACLE = "oracle"
REGISTRY: tuple[Method, ...] = (
    *(_template(q, f, ("nift",) if (q, f) == ("ibs", "nif") else ()) for q in ("bps", "ibs")
      for f in ("ndf", "scf", "nif")),
    Method("cpd", Family.REGISTRATION),  # the demo whose cloud registers best (coherent point drift)
    Method(ORACLE, Family.ORACLE, ("teacher",)),  # the scripted poses at the simulator's true object pose
)
_BY_NAME = {n: m for m in REGISTRY for n in m.names}


def method(name: str) -> Method:
    """The record of a method, by its name or an alias; a one-line ValueError naming the choices."""
    if name not in _BY_NAME:
        raise ValueError(f"unknown method {name!r}; choose one of {', '.join(choices())}")
    return _BY_NAME[name]


def choices(true_poses: bool = True) -> tuple[str, ...]:
    """Every name and alias a user may give (`true_poses`: the oracle's too, where a simulator runs)."""
    return tuple(n for m in REGISTRY if true_poses or not m.true_poses for n in m.names)


def canonical(name: str) -> str:
    """The method's own name for a name or an alias ('nift' -> 'ibs-nif')."""
    return method(name).name
