"""The job cache's former address, kept for the CLI's import of :class:`JobsFailed`; the cache
lives in :mod:`stsf_gym.experiments.jobs.cache`."""

from stsf_gym.experiments.jobs.cache import JobsFailed

__all__ = ["JobsFailed"]
