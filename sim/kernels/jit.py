"""The JIT settings every kernel is compiled with (their own module, so no kernel imports the package face), and
one fix to numba's inliner that cuts up to a third of the time a scheme's kernels take to compile."""

from __future__ import annotations

import copy
import types

from numba import njit  # noqa: F401  (re-exported: every kernel module takes both from here)

JIT = {"cache": True, "nogil": True, "fastmath": False, "error_model": "numpy"}


def _share_scope_copies() -> bool:
    """Make numba's copy of an inlined function's IR linear in its size.

    To inline a callee (`inline="always"`, which the schemes use so the step's loop passes no arrays), numba deep-copies
    its IR block by block, each block with a memo of its own, so every block copies the function's whole scope (every
    variable): blocks x variables objects, up to a third of a scheme's compile time (numba issues #8989 and #9204). Here the
    blocks of one scope share one memo, as one deepcopy of the IR would: the copy has one scope, as the callee has, and
    numba's inliner renames its variables from it alone. The IR and the machine code are the same (the compiled
    trajectories agree to the bit); a numba without this inliner is left as it is."""
    try:
        from numba.core import inline_closurecall as inliner
        from numba.core import ir
    except ImportError:
        return False
    worker = getattr(inliner, "InlineWorker", None)
    if getattr(inliner, "copy", None) is not copy or worker is None or not hasattr(worker, "inline_ir"):
        return False
    memos: dict[int, tuple[object, dict]] = {}

    def deepcopy(x, memo=None):
        if memo is None and isinstance(x, ir.Block):
            scope, memo = memos.get(id(x.scope), (None, None))
            if scope is not x.scope:  # (holding the scope: an id is never taken for another's)
                memo = {}
                memos[id(x.scope)] = (x.scope, memo)
        return copy.deepcopy(x, memo)

    inline_ir = worker.inline_ir

    def inline_ir_sharing(self, *args, **kwargs):
        memos.clear()  # one inlining's copies only (numba compiles under one lock: no two at a time)
        try:
            return inline_ir(self, *args, **kwargs)
        finally:
            memos.clear()

    inliner.copy = types.SimpleNamespace(deepcopy=deepcopy, copy=copy.copy)
    worker.inline_ir = inline_ir_sharing
    return True


SCOPES_SHARED = _share_scope_copies()
