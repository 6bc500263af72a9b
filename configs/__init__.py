"""The package's configuration files (package data, read with :mod:`importlib.resources`)."""
