"""``stsf-gym reproduce table1``: the rig, the two distance measurements, the run and its figure."""
