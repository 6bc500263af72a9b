"""Examples that use stsf-gym as a library (importable from the repository root)."""
