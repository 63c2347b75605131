"""A body's surface split into nested compact groups, for the wave kernels' local expansions (kernels/water.py).

The water's field near a point is one power series in a complex variable whose degree grows with k_max times the
distance to the series' centre (k_max the sea's largest wavenumber). A 20 m float against a 17 m wave needs a degree
the series cannot reach in double precision; a group of its triangles a few metres across needs a low one. So the
triangles (or samples) are ordered by recursive bisection, each node of the tree a contiguous range of that order
with the sphere that holds its items, and the kernels cut the tree, at each pose, where k_max times a node's radius
is small enough (kernels/wet.py). Plain numpy: built once per body.
"""

from __future__ import annotations

import numpy as np

LEAF = 8
"""Items in a node the tree does not split further."""


def bisection_tree(items: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(order (n,) int64, spans (m, 4) int64: start, end, left child, right child (-1: a leaf), spheres (m, 4): centre
    (3,) and radius) of the items (n, k, 3): each item k points, body frame. Node 0 is the root; each node's items are
    order[start:end], split at the median of their centres along the longest side of their box."""
    items = np.asarray(items, dtype=float).reshape(len(items), -1, 3)
    centres = items.mean(axis=1)
    order = np.arange(len(items))
    spans: list[list[int]] = []
    spheres: list[np.ndarray] = []

    def node(start: int, end: int) -> int:
        index = len(spans)
        points = items[order[start:end]].reshape(-1, 3)
        lo, hi = points.min(axis=0), points.max(axis=0)
        centre = 0.5 * (lo + hi)
        spheres.append(np.array([*centre, np.linalg.norm(points - centre, axis=1).max()]))
        spans.append([start, end, -1, -1])
        if end - start > LEAF:
            c = centres[order[start:end]]
            axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
            order[start:end] = order[start:end][np.argsort(c[:, axis], kind="stable")]
            middle = (start + end) // 2
            spans[index][2] = node(start, middle)
            spans[index][3] = node(middle, end)
        return index

    if len(items):
        node(0, len(items))
    else:
        spans.append([0, 0, -1, -1])
        spheres.append(np.zeros(4))
    return order.astype(np.int64), np.array(spans, dtype=np.int64), np.array(spheres)
