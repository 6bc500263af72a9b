"""``stsf-gym sweep``: a sweep file read into cells, their run, and the summary."""
