"""``stsf-gym sweep``: cells over config keys, where they run, and the summary."""
