"""Bodies on joints as one system: the tree and its step (numpy and compiled), its frequency and linear forms, a body's
loads near a twist, what a run shows (its Frame, each body's BodyFrame), the step's stability numbers."""
