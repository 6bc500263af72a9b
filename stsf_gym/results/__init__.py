"""Results: the schema every ``results.json`` follows (:mod:`.schema`) and the provenance each
results file carries (:mod:`.provenance`). The schema's names are re-exported here, where
users import them (``from stsf_gym.results import stat, SCHEMA_VERSION``)."""

from stsf_gym.results.schema import (
    LABEL_KEYS,
    METRICS,
    SCHEMA_VERSION,
    check_rows,
    finite_or_none,
    is_stat,
    render,
    rendered,
    stat,
    stats,
)

__all__ = [
    "LABEL_KEYS",
    "METRICS",
    "SCHEMA_VERSION",
    "check_rows",
    "finite_or_none",
    "is_stat",
    "render",
    "rendered",
    "stat",
    "stats",
]
