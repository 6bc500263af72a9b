"""Training a learnt agent: hyper-parameters, the staged run, its log."""
