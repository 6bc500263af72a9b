"""Vision: the landmark pattern of the paper's Fig. 3 and its detector."""
