"""The job engine: kinds of job, their cache, the local and Ray backends, and ``run_jobs``."""
