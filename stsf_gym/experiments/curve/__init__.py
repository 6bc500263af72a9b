"""``stsf-gym accuracy-curve``: the run and its figure."""
