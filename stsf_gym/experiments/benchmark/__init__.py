"""``stsf-gym benchmark``: agents x pose sources on a suite's test worlds, declared arrival."""
