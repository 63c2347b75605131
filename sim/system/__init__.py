"""Bodies on joints as one system: the tree, its step (numpy and compiled), its frequency and linear forms, the running assembly, the step's stability numbers."""
