"""How every kernel is compiled (their own module, so no kernel imports the package face): the JIT settings, `njit`,
which compiles a kernel called by other kernels once, as a part of its callers only, and one fix to numba's inliner
that cuts up to a third of the time a scheme's kernels take to compile."""

from __future__ import annotations

import copy
import functools
import types

import numba
from numba.core import compiler, event, utils
from numba.core import types as nbtypes
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler_lock import require_global_compiler_lock
from numba.core.extending import lower_builtin, type_callable
from numba.core.registry import cpu_target
from numba.core.typing.templates import builtin_registry
from numba.np import arrayobj

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


class _LinkOnly(JITCodeLibrary):
    """A kernel's code as its callers take it: finalising it links its own callees' code in, and no more. numba
    finalises a library it links by optimising it and emitting its machine code, which each caller then does again
    with the callee's code in its own (linked, inlined, emitted anew): work done for nothing."""

    def finalize(self):
        require_global_compiler_lock()
        self._raise_if_finalized()
        for library in dict.fromkeys(self._linking_libraries):
            self._reload_init.update(library._reload_init)
            self._final_module.link_in(library._get_module_for_linking(), preserve=True)
        self._finalized = True


class Kernel:
    """A compiled function. Called from Python: a numba dispatcher (its code cached on disk). Called from another
    kernel: a subroutine, typed and lowered once per argument types and linked into its callers, whose own
    optimisation and machine code hold it; never optimised, emitted or cached alone, and with no Python wrapper.

    What it saves (issue 57): a numba dispatcher called by another compiles in full (LLVM's optimisation, machine code,
    a Python wrapper, a cache file) and is then compiled again inside each caller; a spec's step, frame and start over
    the same loads paid that at every level of the calls. The moored buoy's kernels: 131 -> 68 CPU s, drop 32 -> 22,
    rm3 122 -> 59, storm 76 -> 38 (the same machine, both at once); the machine code, and so each trajectory, is the
    same to the bit."""

    def __init__(self, f, options: dict):
        functools.update_wrapper(self, f)
        self.py_func = f
        self.dispatcher = numba.njit(**options)(f)
        self._error_model = options.get("error_model", "python")
        self._subroutines: dict = {}
        type_callable(self)(self._typer)
        lower_builtin(self, nbtypes.VarArg(nbtypes.Any))(self._lower)

    def __call__(self, *args, **kwargs):
        return self.dispatcher(*args, **kwargs)

    def __getattr__(self, name):  # the dispatcher's overloads, stats, ... (not _numba_type_: a kernel types as itself)
        if name.startswith("_") or name == "dispatcher":
            raise AttributeError(name)
        return getattr(self.dispatcher, name)

    def subroutine(self, args: tuple):
        """numba's compile result for these argument types, compiled on first use (under numba's compiler lock: it is
        called while a caller is typed or lowered)."""
        args = tuple(nbtypes.unliteral(a) for a in args)
        if args not in self._subroutines:
            flags = compiler.Flags()
            flags.nrt = True
            flags.no_compile = flags.no_cpython_wrapper = flags.no_cfunc_wrapper = True
            flags.error_model = self._error_model
            target = cpu_target.target_context
            library = _LinkOnly(target.codegen(), self.py_func.__qualname__)
            with event.trigger_event("numba:compile", data={"dispatcher": self, "args": args, "return_type": None}):
                self._subroutines[args] = compiler.compile_internal(
                    cpu_target.typing_context, target, library, self.py_func, args, None, flags, locals={}
                )
        return self._subroutines[args]

    def _typer(self, context):
        def typer(*args):
            return self.subroutine(args).signature.return_type

        typer.pysig = utils.pysignature(self.py_func)  # (the caller's lowering then passes the arguments one by one)
        return typer

    def _lower(self, context, builder, sig, args):
        compiled = self.subroutine(sig.args)
        context.active_code_library.add_linking_library(compiled.library)
        args = [context.cast(builder, value, given, taken) for value, given, taken in zip(args, sig.args, compiled.signature.args)]
        return context.call_internal(builder, compiled.fndesc, compiled.signature, args)


def njit(**options):
    """The kernels' decorator: numba's own where the kernel is to be inlined into its callers' IR (inline="always"),
    a Kernel otherwise."""
    if options.get("inline", "never") != "never":
        return numba.njit(**options)
    return lambda f: Kernel(f, options)


def _plain_shape_errors() -> bool:
    """Have a slice assignment of a wrong shape raise numba's plain message ("cannot assign slice from input of different
    size"), not its CPU message, which formats both shapes: that f-string compiles numba's whole string machinery
    (repr, join, concatenation) into every process that compiles a kernel, 4-6 CPU s of a 20 s compile, for an error
    the kernels never raise. Measured both at once: drop 24-26 -> 18-20 CPU s, moored-buoy 63 -> 56. A numba without
    both overloads is left as it is."""
    cpu, plain = (getattr(arrayobj, name, None) for name in ("ol_raise_with_shape_context_cpu", "ol_raise_with_shape_context_generic"))
    for func, typ in builtin_registry.globals:
        if func is getattr(arrayobj, "raise_with_shape_context", None) and plain is not None:
            for template in getattr(typ, "templates", ()):
                if getattr(template, "_overload_func", None) is cpu:
                    template._overload_func = staticmethod(plain)
                    return True
    return False


PLAIN_SHAPE_ERRORS = _plain_shape_errors()
